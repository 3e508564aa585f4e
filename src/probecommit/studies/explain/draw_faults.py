"""The fault harness's boundary and particle arms on fresh draws of Split B's test generator.

Table VIII's boundary row and the particle fault's signature are statistics of one 96-instance
draw (the harness's). Each fresh draw's corrected-model replay (``runs.fresh_draws``) stands in
for the harness's base rollout (the same scene boundary hg + delta, random probes, the corrected
model), and the harness's own arms (``studies.faults.fault_arms``) are replayed on it: the range
over draws is what a draw of our generator gives for each cell.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.surprise import surprise_auc
from probecommit.studies.explain.replay_final import replay_at
from probecommit.studies.faults import fault_arms

#: The faults whose arms replay the base rollout and that the claims compare.
FAULTS = ("none", "boundary", "particles")


def _probe(episodes: pd.DataFrame, k: int) -> pd.DataFrame:
    return episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok") & (episodes["k"] == k)]


def arm_cells(episodes: pd.DataFrame, kmax: int) -> dict[str, float]:
    """Per fault: failure, optimism and the surprise AUC (escape at ``kmax``) of its fault arm, and the tempered
    arm's failure; the cells of Table VIII and Fig. 7 at ``kmax``. ``episodes`` carries ``fault`` and ``arm``."""
    out: dict[str, float] = {}
    for fault in FAULTS:
        rows = episodes[(episodes["fault"] == fault) & (episodes["arm"] == "fault")]
        last = _probe(rows, kmax)
        if last.empty:
            continue
        out[f"{fault}.fail"] = float(last["realized"].mean())
        out[f"{fault}.optimism"] = float((last["realized"] - last["predicted"]).mean())
        out[f"{fault}.escape"] = float(last["escaped"].mean())
        if last["escaped"].any() and not last["escaped"].all():
            auc = surprise_auc(rows[rows["method"] == "probe_robust"], budgets=[kmax], final_k=kmax, resamples=2, seed=0)
            out[f"{fault}.surprise_auc"] = float(auc["auc"].iloc[0])
        tempered = _probe(episodes[(episodes["fault"] == fault) & (episodes["arm"] == "tempered")], kmax)
        if len(tempered):
            out[f"{fault}.tempered"] = float(tempered["realized"].mean())
    if "particles.optimism" in out and "none.optimism" in out:
        out["particles_residual_improves"] = float(out["particles.optimism"] < out["none.optimism"])
    return out


def draw_cells(base: Any, faults: Any, sigma: float, kmax: int) -> dict[str, float]:
    """``arm_cells`` of the harness's base-rollout arms replayed on one draw's corrected run ``base``."""
    arms = [a for a in fault_arms(faults.noise_factor, faults.prior_half_width, faults.particles, faults.frame_offset,
                                  faults.temperature, sigma) if a.rollout == "base" and a.fault in FAULTS]
    return arm_cells(harness_at(base, arms, kmax), kmax)


def harness_at(base: Any, arms: list[Any], k: int) -> pd.DataFrame:
    """``run_fault_harness({"base": base}, arms, chunk_instances=48)``'s rows at budget ``k`` (every cell
    :func:`arm_cells` reads is there, the surprise AUC's label and reading included): each distinct replay
    committed at ``k`` only (``replay_at``: the same rows; the other budgets were most of its CPU, issue 42)."""
    frames, replayed = [], {}
    for arm in arms:
        key = json.dumps(arm.overrides, sort_keys=True, default=str)
        if key not in replayed:
            replayed[key] = replay_at(base, arm.overrides, k)
        frames.append(replayed[key].assign(fault=arm.fault, arm=arm.arm))
    return pd.concat(frames, ignore_index=True)


def nan_spread(per_draw: list[dict[str, float]]) -> dict[str, float]:
    """Per cell ``min``, ``max``, ``mean`` over the draws where the cell is defined, and ``n`` of them."""
    frame = pd.DataFrame(per_draw)
    out: dict[str, float] = {}
    for cell in frame.columns:
        values = frame[cell].dropna().to_numpy(float)
        if values.size:
            out[f"{cell}.min"], out[f"{cell}.max"] = float(np.min(values)), float(np.max(values))
            out[f"{cell}.mean"] = float(np.mean(values))
        out[f"{cell}.n"] = int(values.size)
    return out
