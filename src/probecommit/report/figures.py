"""Figures (matplotlib, Agg backend; no display needed)."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Sequence

import matplotlib

from probecommit.report.backend import use_agg_unless_chosen  # noqa: E402

use_agg_unless_chosen()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit.report.style import COLUMN  # noqa: E402  (applies the shared style)
from probecommit.store.safefile import write_bytes, write_with  # noqa: E402


def save_figure(fig, path: str | Path, dpi: int | None = None, caption: str | None = None) -> Path:
    """Write ``fig`` as PNG (``path``, 300 dpi) and PDF beside it, then close it.

    The PDF carries no creation date, so the same figure is the same bytes (frozen
    results are hashed). Figures are built in loops; open ones leak, hence the close.
    ``caption`` (written from the data: n, what a band is) travels inside both files (PNG
    ``Description``, PDF ``Subject``), where the HTML report reads it: no sidecar file.

    Returns:
        The PNG path.
    """
    path = Path(path)
    png = path.with_suffix(".png")
    png.parent.mkdir(parents=True, exist_ok=True)
    from probecommit.report.style import text_sizes

    pdf_meta = {"CreationDate": None, **({"Subject": caption} if caption else {})}
    pdf = io.BytesIO()
    fig.savefig(pdf, format="pdf", metadata=pdf_meta)  # first: its draw places the text the PNG's metadata reads
    sizes = [size for size, _ in text_sizes(fig, drawn=True)]
    # the smallest text, so a page showing the PNG can keep it legible (HTML reports read it back)
    meta = {"MinFontPt": f"{min(sizes):.2f}" if sizes else "", "Dpi": str(dpi or 300)}
    png_meta = {**meta, **({"Description": caption} if caption else {})}
    write_with(png, lambda buf: fig.savefig(buf, format="png", dpi=dpi or 300, metadata=png_meta))
    write_bytes(png.with_suffix(".pdf"), pdf.getvalue())
    plt.close(fig)
    return png


def read_caption(png: str | Path) -> str | None:
    """The caption :func:`save_figure` stored in a PNG, or None."""
    from PIL import Image

    try:
        with Image.open(png) as image:
            return image.info.get("Description") or None
    except OSError:
        return None


def min_font_px(png: str | Path) -> float | None:
    """The smallest text of a PNG written by :func:`save_figure`, in image pixels (None if unknown)."""
    from PIL import Image

    try:
        with Image.open(png) as image:
            pt, dpi = image.info.get("MinFontPt"), image.info.get("Dpi")
            if not pt and "dpi" in image.info:  # written before the size was stored: the style's floor at its dpi
                from probecommit.report.style import MIN_FONT

                pt, dpi = MIN_FONT, image.info["dpi"][0]
    except OSError:
        return None
    return float(pt) * float(dpi) / 72 if pt and dpi else None


def belief_density(z: np.ndarray, weights: np.ndarray, grid: np.ndarray, bandwidth: float) -> np.ndarray:
    """Weighted Gaussian-kernel density of particles on ``grid``, peak-normalized."""
    diff = (grid[:, None] - z[None, :]) / bandwidth
    dens = np.exp(-0.5 * diff * diff) @ weights
    peak = dens.max()
    return dens / peak if peak > 0 else dens


def belief_snapshots(
    trace,
    model,
    episodes: pd.DataFrame,
    episode_row: int,
    budgets: Sequence[int],
    path: str | Path,
    title: str | None = None,
) -> Path:
    """Peak-normalized beliefs over the decision coordinate after chosen budgets (Fig. 1b).

    Args:
        trace: A ``BeliefTrace`` holding the episode.
        model: The model (decision coordinate, action grid).
        episodes: Episode rows of that trace (to mark each budget's committed aim).
        episode_row: Row of the episode within the trace batch.
        budgets: Budgets to draw, e.g. ``(1, 3, 5)``.
        path: Output PNG.
    """
    return draw_belief_snapshots(belief_series(trace, model, episodes, episode_row, budgets), path, title)


def belief_series(trace, model, episodes: pd.DataFrame, episode_row: int, budgets: Sequence[int]) -> pd.DataFrame:
    """Fig. 1b's data series, one table (what a publication stores and ``verify`` draws again):
    ``part`` ``belief`` (each budget's particles ``z`` and ``weight``), ``aim`` (each budget's committed
    aim and whether it entered), ``tap`` (each tap ``u`` and its reading ``y``, in order); the truth and
    the prior's bounds on every row."""
    batch = trace.batch
    iid, rep = str(batch.instance_id[episode_row]), int(batch.repeat[episode_row])
    parts = []
    for k in budgets:
        state = trace.states[k]
        parts.append(pd.DataFrame({"part": "belief", "k": int(k), "z": np.asarray(model.decision(state.particles[episode_row]), float),
                                   "weight": np.asarray(state.weights[episode_row], float)}))
        row = episodes[(episodes.instance_id == iid) & (episodes.repeat == rep) & (episodes.k == k) & (episodes.method == "probe_robust")]
        if len(row):
            parts.append(pd.DataFrame({"part": ["aim"], "k": [int(k)], "z": [float(row["action"].iloc[0])],
                                       "weight": [float(float(row["realized"].iloc[0]) == 0)]}))
    taps = batch.u[episode_row, : max(budgets)].reshape(-1)
    readings = batch.y[episode_row, : max(budgets)].reshape(len(taps), -1)[:, 0]
    parts.append(pd.DataFrame({"part": "tap", "k": np.arange(1, len(taps) + 1), "z": taps.astype(float),
                               "weight": readings.astype(float)}))
    return pd.concat(parts, ignore_index=True).assign(
        z_true=float(model.decision(batch.truths[episode_row])), low=float(model.prior_low[0]),
        high=float(model.prior_high[0]))


def draw_belief_snapshots(series: pd.DataFrame, path: str | Path, title: str | None = None) -> Path:
    """Fig. 1b from its data series (:func:`belief_series`): a belief per budget, its aim on top (filled:
    the peg entered), the taps below, numbered in order."""
    first = series.iloc[0]
    lo, hi, z_true = float(first["low"]), float(first["high"]), float(first["z_true"])
    beliefs = series[series["part"] == "belief"]
    aims = series[series["part"] == "aim"]
    budgets = list(dict.fromkeys(int(k) for k in beliefs["k"]))
    grid = np.linspace(lo - 1, hi + 1, 600)
    colors = plt.cm.viridis(np.linspace(0.15, 0.85, len(budgets)))
    fig, ax = plt.subplots(figsize=(COLUMN, 3.1))
    for color, k in zip(colors, budgets):
        b = beliefs[beliefs["k"] == k]
        ax.plot(grid, belief_density(b["z"].to_numpy(), b["weight"].to_numpy(), grid, 0.3), color=color, label=f"after tap {k}")
        aim = aims[aims["k"] == k]
        if len(aim):
            ok = bool(aim["weight"].iloc[0])
            ax.plot([float(aim["z"].iloc[0])], [1.08], marker="v", ms=5, color=color, markerfacecolor=color if ok else "white")
    ax.axvline(z_true, color="crimson", ls="--", lw=1.0, label="true hole")
    # Each tap: its order and what it read (top of the plate or the pocket floor).
    taps = series[series["part"] == "tap"]
    seen: dict[float, int] = {}
    for j, (u, y) in enumerate(zip(taps["z"].to_numpy(), taps["weight"].to_numpy()), start=1):
        level = seen.get(float(u), 0)
        seen[float(u)] = level + 1
        pocket = y < -7.5
        ax.plot([u], [-0.07], marker="v" if pocket else "s", ms=3.5, color="k", markerfacecolor="k" if pocket else "white")
        ax.annotate(str(j), (u, -0.07), xytext=(0, -7 - 6 * level), textcoords="offset points", ha="center", fontsize=7)
    ax.plot([], [], "ks", ms=3.5, markerfacecolor="white", label="tap read top")
    ax.plot([], [], "kv", ms=3.5, label="tap read pocket")
    ax.set_xlim(grid[0], grid[-1])
    ax.set_ylim(-0.32, 1.18)
    ax.set_xlabel("hole position (mm)")
    ax.set_ylabel("belief (peak-normalized)")
    ax.set_title(title or "beliefs after each budget; aims on top (filled: entered)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False, ncol=3, handlelength=1.2,
              columnspacing=0.8)
    fig.tight_layout()
    caption = (f"Peak-normalized particle beliefs over the hole position after taps {', '.join(map(str, budgets))} of one "
               f"simulated insertion episode; dashed: the true hole; triangles on top: each budget's aim (filled: the "
               f"peg entered); markers below: the taps, numbered in order (square: read the top; triangle: the pocket).")
    return save_figure(fig, path, caption=caption)
