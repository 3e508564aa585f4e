"""Table III's original arm with one fixed tap before the random ones (E203, E204; docs/decisions.md, "ex34").

Why: "the robot's probes are uniform random unless stated", and how a budget counts its taps is not. A pipeline whose
random-probe trajectories begin with one tap at a fixed position has another exposure to the misread band at every
budget than ours (a fixed tap lands in the band of a share of the prior box that depends on its position, a uniform
tap in 0.147 of it), which is where the original model's optimism lives (ex20). The two positions are the ones the
paper's text gives a reason for, declared before any number: the first tap of its cover schedule (-12 mm) and the
centre of the tap grid and prior box (0 mm). For each, every trajectory of Table III's run gets one tap at that
position before its eight stored random taps (one engine query per trajectory, the run's cached MuJoCo answers, plus
the simulator's noise), the beliefs are recomputed over the nine taps and committed as Table III's original arm at
every tap count; ex20's post-stratified estimator reads the cells at the design's exact exposure for this design. It
stores its rows, so ``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex20, ex20_band, ex31_shift, stored

#: The result group this step fills, and the rows its keys are summarized from.
GROUP = "ex34_fixed"
GROUPS = (GROUP,)
STORED = "ex34_fixed_rows.parquet"
STORED_BY_GROUP = {GROUP: STORED}
#: Per experiment: its key prefix, the fixed tap's position (mm) and its noise generator's tag (declared).
POSITIONS = {"E203": ("cover_first", -12.0, 203), "E204": ("centre", 0.0, 204)}
#: Taps per trajectory after the fixed one is put first (the run's eight random taps follow it).
TAPS = 9
#: Table III's budgets read as k taps in all (the rules' reading) and as the fixed tap plus k random taps (beside).
BUDGETS = ex20_band.BUDGETS
PLUS = {k: k + 1 for k in BUDGETS}


def prepended(loaded: Any, u0: float, tag: int) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The run's trajectories with a tap at ``u0`` put first: its reading the run's engine answer at the truth plus the
    simulator's noise (one generator seeded ``(run seed, tag)``, drawn in the run's episode order), the beliefs
    recomputed under the run's config and committed by its probe-robust executor at every tap count 1..9.
    Returns ``(episodes, probes)`` as the run's tables are shaped (``ex20_band.band_rows`` reads them)."""
    from probecommit.runner.build import build_filter, build_model, config_executors
    from probecommit.runner.inference import build_trace, commit
    from probecommit.runner.replay import probe_batch, simulator_for_run

    cfg = loaded.config
    model = build_model(cfg)
    batch = probe_batch(loaded, model)
    sim = simulator_for_run(loaded, cfg)
    rng = np.random.default_rng((int(cfg.seed), int(tag)))
    tap = np.array([u0], dtype=float)
    y0 = np.stack([sim.probe(theta, tap, rng) for theta in batch.truths])
    batch = dataclasses.replace(batch, u=np.concatenate([np.full((batch.n_episodes, 1, 1), u0), batch.u], axis=1),
                                y=np.concatenate([y0[:, None, :], batch.y], axis=1))
    trace = build_trace(build_filter(model, cfg.belief), batch, cfg.seed, range(1, TAPS + 1), keep_prior=False)
    episodes = commit(trace, model, sim, config_executors(cfg, model, ("probe_robust",)), thresholds=cfg.belief.nu)
    return episodes, batch.probes_frame()


def rows_at(loaded: Any, experiment: str) -> pd.DataFrame:
    """ex20's rows (one per trajectory and tap count 1..9) of the rerun with ``experiment``'s fixed tap first."""
    label, u0, tag = POSITIONS[experiment]
    episodes, probes = prepended(loaded, u0, tag)
    rows = ex20_band.band_rows(episodes, probes, loaded.instances, label, ex20._design(loaded), range(1, TAPS + 1))
    return rows.assign(fixed=u0)


def position_keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """One position's keys: ex20's post-stratified cells at the design's exposure with the fixed tap first, read as k
    taps in all (``.k<k>``, the rule's) and as the fixed tap plus k random taps (``plus.*.k<k>``), and the escape at
    every tap count (``escape*.k<taps>``, raw and post-stratified)."""
    from probecommit.tasks.insertion.model import InsertionModel

    positions = [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]
    first = rows.iloc[0]
    design = {n: float(first[n]) for n in ex20_band.DESIGN}
    taps = sorted(int(k) for k in rows["k"].unique())
    probabilities = ex20_band.design_probabilities(positions, design, taps, fixed=float(first["fixed"]))
    res, seed = int(boot["resamples"]), int(boot["seed"])
    out = dict(ex20_band.frozen_keys(rows[rows["k"].isin(BUDGETS)], probabilities, res, seed))
    plus = ex20_band.frozen_keys(rows[rows["k"].isin(list(PLUS.values()))], probabilities, res, seed)
    for name, value in plus.items():  # renamed by Table III's budget: ``.k<k + 1>`` -> ``plus.<name>.k<k>``
        base, _, at = name.rpartition(".k")
        if base and int(at) - 1 in PLUS:
            out[f"plus.{base}.k{int(at) - 1}"] = value
    out.update(ex31_shift.escape_keys(rows, probabilities))
    out["fixed"] = float(first["fixed"])
    out["f_band"] = probabilities[1][0]
    return out


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Every key of the step from its stored rows, per experiment under its prefix."""
    out: dict[str, Any] = {}
    for label, _, _ in POSITIONS.values():
        at = rows[rows["draw"] == label]
        if len(at):
            out.update({f"{label}.{n}": v for n, v in position_keys(at, boot).items()})
    return out


def run(job: Any) -> None:
    """E203 and E204 on Table III's stored random test run, each with its fixed tap put first."""
    job.progress("explain: Table III's original arm with one fixed tap before the random ones", 0, 1)
    loaded = job.load(ex20_band.FROZEN)
    rows = pd.concat([rows_at(loaded, e) for e in POSITIONS], ignore_index=True)
    job.stored[STORED] = rows
    job.res[GROUP].update(keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, GROUP, STORED, lambda rows: keys(rows, boot))
