"""PyBullet's capture window against the spread the paper reports for it (E30).

Why: the paper's PyBullet capture window is 1.21 x the analytic one "with SD 0.69 of that
ratio across the 24 development truths"; ours is 1.000 with an SD near 1e-4. A mean over 24
truths with that SD has a standard error of 0.69 / sqrt(24): the interval below is the
paper's own sampling interval of its mean (normal approximation), computed from its printed
mean and SD and the number of truths both scans use. It says whether the paper's mean is
distinguishable from ours given its own spread; it does not say why the paper's per-truth
ratios spread so much more than ours.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from probecommit.studies.paper_values import value

Z95 = 1.959963984540054


def mean_interval(mean: float, sd: float, n: int) -> list[float]:
    """``[mean, lo, hi]``: the 95 % normal-approximation interval of a mean of ``n`` values with SD ``sd``."""
    half = Z95 * sd / math.sqrt(n)
    return [mean, mean - half, mean + half]


def run(root: Path) -> dict[str, Any]:
    """Keys of ``explain:results.engines_x`` (empty when the engines study is not under ``root``)."""
    path = root / "engines" / "results" / "results.json"
    if not path.is_file():
        return {}
    capture = json.loads(path.read_text())["results"]["scans"]["pybullet"]["capture"]
    n = int(capture["truths"])
    iv = mean_interval(value("T18-engine-scans.pybullet_ratio"), value("T18-engine-scans.pybullet_ratio_sd"), n)
    ours = float(capture["ratio_mean"])
    return {"pybullet_capture.ours": ours, "pybullet_capture.ours_sd": float(capture["ratio_sd"]),
            "pybullet_capture.truths": n, "pybullet_capture.paper_mean_interval": iv,
            "pybullet_capture.ours_inside_paper_interval": int(iv[1] <= ours <= iv[2])}
