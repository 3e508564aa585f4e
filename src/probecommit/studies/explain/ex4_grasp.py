"""Grasp's worsening truths against the squeeze's resolution (E49).

Why: the paper's grasp numbers imply that probing succeeds on every seed of the truths its blind
grip holds (they tie); ours succeeds on only part of the seeds of ours, so they worsen (E47:
the same on the model-exact scene). The suspected cause is how much a squeeze tells about the
hold force: its slip scale (set by our unreported squeeze duration) against the paper's
sigma = 2 mm. Scaling the slip by ``c`` is the same inference as scaling the noise by ``1/c``
(the likelihood reads slip / sigma), so the step reruns E47's model-exact grasp study with the
model's and the scene's sigma divided by each declared ``c`` and counts the per-truth signs as
Table II reads them (docs/decisions.md, "ex4"). Removing the cause must remove the worsening.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.runner.config import config_data, parse_config
from probecommit.runner.study import run_study
from probecommit.studies.breadth import paper_config, quick_config
from probecommit.studies.breadth import truth_rows
from probecommit.studies.explain.grasp_x import sign_counts


def resolution_config(c: float, quick: bool) -> Any:
    """The frozen grasp config on the analytic scene with both sigmas divided by ``c``."""
    base = paper_config("grasp")
    data = config_data(quick_config(base) if quick else base)
    data["name"] = f"grasp_analytic_resolution{c:g}"
    data["simulator"] = {**data["simulator"], "engine": "analytic",
                         "noise_sigma": float(data["simulator"]["noise_sigma"]) / c}
    data["model"] = {**data["model"], "sigma": float(data["model"]["sigma"]) / c}
    return parse_config(data)


#: The rows the keys are counted from (``truth_rows`` of each rerun, ``part`` = ``c<factor>``, and of E47's frozen
#: run, ``part`` = ``frozen``): stored beside results.json, so verify counts the keys again (``keys``).
STORED = "ex4_grasp_rows.parquet"


def run(runs: Path, factors: list[float], quick: bool, workers: int = 1) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys of ``explain:results.ex4_grasp`` (``keys``) and the rows they are counted from: per factor ``c``, the
    feasible truths, their signs and the worst truth's difference (the frozen resolution's worst, c = 1, from E47's
    run when it is there)."""
    frames = []
    for c in factors:
        config = resolution_config(float(c), quick)
        path = runs / config.name
        run_study(config, path, workers=workers, threads=1)
        frames.append(truth_rows(config, path).assign(part=f"c{float(c):g}", factor=float(c)))
    frozen = runs / "grasp_analytic_scene"  # E47's run: the frozen resolution (c = 1) on the same scene
    if (frozen / "episodes.parquet").is_file():
        frames.append(truth_rows(resolution_config(1.0, quick), frozen).assign(part="frozen", factor=1.0))
    rows = pd.concat(frames, ignore_index=True)
    return keys(rows), rows


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """The keys from the stored rows (one function for the explain step and verify)."""
    reruns = rows[rows["part"] != "frozen"]
    out: dict[str, Any] = {"factors": [float(c) for c in pd.unique(reruns["factor"])]}
    for part, r in reruns.groupby("part", sort=False):
        out.update({f"{part}.{k}": v for k, v in sign_counts(r.drop(columns=["part", "factor"]), worst=True).items()})
    frozen = rows[rows["part"] == "frozen"]
    if len(frozen):
        out["c1.worst_difference"] = sign_counts(frozen.drop(columns=["part", "factor"]), worst=True)["worst_difference"]
    return out
