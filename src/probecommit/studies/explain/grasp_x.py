"""Grasp's per-truth signs with the model as the scene's truth (E47).

Why: the paper reports grasp descriptively: of six feasible truths three improve and three tie,
none worsens. Ours: 13 of 16 truths feasible, 10 improve, 3 worsen. The grasp scene is ours
throughout (the paper gives its latents, probe, sigma, budgets and 16 x 80, nothing else):
the force balance the belief uses is checked against a MuJoCo lift. A truth can worsen under
probing only if the belief, sharpened by squeezes, commits to a grip the scene rejects where
the blind prior's grip passes: a mismatch between the model and the scene. This step removes
that mismatch: the same frozen study (truths, seeds, probes, methods) on the analytic scene,
whose lift is the model's force balance itself, and the same per-truth sign count.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.runner.config import config_data, parse_config
from probecommit.runner.study import run_study
from probecommit.studies.breadth import FAMILY_K, paper_config, quick_config, sign_flip_summary, truth_rows


#: The model-exact grasp run's rows Table II's sign count reads, with each instance's feasibility and truth label.
STORED = "grasp_analytic_episodes.parquet"


def sign_counts(rows: pd.DataFrame, worst: bool = False) -> dict[str, Any]:
    """Feasible truths and their per-truth signs (Probe-Robust(k) - Blind-Bayes success), as Table II reads them,
    from the stored rows (``breadth.truth_rows``; one function for the explain step and verify); with ``worst``,
    also the lowest per-truth difference (``worst_difference``, how far the worst truth falls)."""
    out = sign_flip_summary(rows, FAMILY_K["grasp"])
    differences = out.pop("differences")
    if worst:
        out["worst_difference"] = min(differences.values(), default=float("nan"))
    return out


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.grasp_signs`` from the stored rows."""
    return {f"analytic.{k}": v for k, v in sign_counts(rows).items()}


def run(runs: Path, quick: bool, workers: int = 1) -> pd.DataFrame:
    """The frozen grasp study on the analytic (model-exact) scene: its stored rows (``keys`` reads them)."""
    base = paper_config("grasp")
    base = quick_config(base) if quick else base
    data = config_data(base)
    data["name"] = "grasp_analytic_scene"
    data["simulator"] = {**data["simulator"], "engine": "analytic"}
    config = parse_config(data)
    path = runs / "grasp_analytic_scene"
    run_study(config, path, workers=workers, threads=1)
    return truth_rows(config, path)
