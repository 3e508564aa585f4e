"""Fig. 2: the probe-then-commit pipeline and its offline audit, drawn by code (matplotlib).

Page width (7.16 in). Boxes are the paper's stages; arrows its data flow; the dashed
loop is the correction that applies between deployments, never within an episode.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

from probecommit.report.figures import save_figure  # noqa: E402
from probecommit.report.style import DOUBLE  # noqa: E402

#: (key, x, y, width, height, title, detail, colour): the stages, in data coordinates of a 100 x 32 canvas.
BOXES = (
    ("probe", 2, 19, 15, 9, "probe", "tap uⱼ, read yⱼ\n(k taps)", "#dbe8f6"),
    ("belief", 22, 19, 17, 9, "belief bₖ", "particle filter:\nreweight, resample", "#dbe8f6"),
    ("retain", 44, 19, 17, 9, "retained set", "top-mass ν\nscenarios", "#dbe8f6"),
    ("commit", 66, 19, 15, 9, "commit", "one action aₖ,\npredicted R̂ₖ", "#dbe8f6"),
    ("outcome", 86, 19, 12, 9, "outcome", "realized Rₖ\n(once)", "#f3f3f3"),
    ("coverage", 22, 3, 22, 9, "coverage audit", "truth in the retained\ninterval? escape?", "#fbe5cc"),
    ("optimism", 54, 3, 22, 9, "optimism audit", "eₖ = Rₖ − R̂ₖ\n(mean over episodes)", "#fbe5cc"),
)
def _anchor(box: tuple, side: str) -> tuple[float, float]:
    _, x, y, w, h, *_ = box
    return {"left": (x, y + h / 2), "right": (x + w, y + h / 2), "top": (x + w / 2, y + h), "bottom": (x + w / 2, y)}[side]


def pipeline_figure(path: str | Path) -> Path:
    """Draw Fig. 2 into ``path`` (PNG + PDF)."""
    fig, ax = plt.subplots(figsize=(DOUBLE, 2.5))
    ax.set_xlim(0, 100)
    ax.set_ylim(-4, 33)
    ax.set_axis_off()
    boxes = {b[0]: b for b in BOXES}
    for key, x, y, w, h, title, detail, colour in BOXES:
        ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.4,rounding_size=1.2", fc=colour, ec="0.3", lw=0.8))
        ax.text(x + w / 2, y + h - 2.2, title, ha="center", va="center", fontsize=8, fontweight="bold")
        ax.text(x + w / 2, y + h / 2 - 1.6, detail, ha="center", va="center", fontsize=7, linespacing=1.1)

    def arrow(a, b, **kw):
        ax.add_patch(FancyArrowPatch(a, b, arrowstyle="-|>", mutation_scale=8, lw=0.9, color="0.2", **kw))

    for src, dst in (("probe", "belief"), ("belief", "retain"), ("retain", "commit"), ("commit", "outcome")):
        arrow(_anchor(boxes[src], "right"), _anchor(boxes[dst], "left"))
    # the probe loop: the belief asks for the next tap until the budget is spent
    arrow((boxes["belief"][1] + 4, 28.6), (boxes["probe"][1] + 11, 28.6), connectionstyle="arc3,rad=0.5")
    ax.text(19.5, 32.2, "next tap", ha="center", fontsize=7)
    arrow(_anchor(boxes["retain"], "bottom"), (33, 12.4))
    arrow(_anchor(boxes["commit"], "bottom"), (65, 12.4))
    arrow(_anchor(boxes["outcome"], "bottom"), (76.4, 9), connectionstyle="arc3,rad=-0.3")
    ax.text(0.5, 16.2, "on the robot, per episode", fontsize=7, color="0.35", ha="left")
    ax.text(0.5, 0.5, "offline,\nwith ground\ntruth", fontsize=7, color="0.35", ha="left", va="bottom")
    # the outcome of the audits: what each failure prompts; corrections between deployments
    ax.text(33, -2.4, "coverage fails → inspect the belief model", ha="center", fontsize=7, color="#a0522d")
    ax.text(65, -2.4, "optimism → validate score and execution model", ha="center", fontsize=7, color="#a0522d")
    ax.plot([0.5, 99.5], [15.5, 15.5], color="0.6", lw=0.6, ls=(0, (4, 3)))
    fig.tight_layout(pad=0.1)
    caption = ("Probe-then-commit execution (top) and the offline audit (bottom): probes update the belief; retained "
               "scenarios select an action and its failure score; audits with ground truth assess decision-coordinate "
               "coverage and score optimism separately. Corrections apply between deployments, not within an episode.")
    return save_figure(fig, path, caption=caption)
