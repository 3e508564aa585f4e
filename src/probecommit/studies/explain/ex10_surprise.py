"""The cover schedule's surprise AUC when the belief keeps no particle its taps contradict (E88).

Why: on the paper's schedule every trajectory taps -12 mm first, so the k = 1 surprise AUC for
final-budget escape says only how many escapes read the pocket there; the paper's 0.85 needs most
of its 50 escapes to, ours has 5 of 28. Those trajectories (holes about -8.6 to -6.5 mm) read a
pocket the deployed boundary gives only to holes below about -8.4 mm: the belief is confidently
wrong, yet its full hull covers them, since the first tap's resampled copies are jittered by
N(0, 0.6 mm) and no later tap of the schedule contradicts that tail.

The test removes the tail and nothing else: the paper's-schedule Split B test run (its instances,
taps and readings) replayed with the filter's resample-move (``belief.move: mh``: the jitter is the
proposal, a moved copy that contradicts a tap already seen is rejected), and, beside it, with the
jitter switched off; each trajectory relabelled by the paper's rule (outside the full hull at the
final budget) and its density surprise (running max) ranked against that label. The label, the
reading and the taps are the paper's; only the belief's tail differs.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_auc
from probecommit.runner.replay import LoadedRun, RunBeliefs, replay_config
from probecommit.studies.explain.ex10_boundary import outside_hull

#: The stored rows (filter, trajectory, budget, surprise, final-budget label) the summaries come from.
STORED = "ex10_surprise_rows.parquet"
#: The filters replayed: as run (the paper's jitter), resample-move, no jitter (``belief`` overrides).
FILTERS = {"as_run": {}, "mh": {"move": "mh"}, "no_jitter": {"jitter": False}}
#: A reading below this (mm) is the pocket floor (-15 mm), above it the plate top (0 mm).
POCKET_CUT_MM = -7.5


def filter_config(config: Any, overrides: dict[str, Any]) -> Any:
    """``config`` with its belief settings overridden (``{}``: the run's own)."""
    return replay_config(config, {"belief": overrides})


def filter_rows(run: LoadedRun, name: str, final_k: int, chunk_instances: int = 48) -> pd.DataFrame:
    """One row per trajectory and budget (1 and ``final_k``) under filter ``name``: the density surprise (running
    max of the stored-definition -log predictive density) and whether the truth is outside the full hull at
    ``final_k``, and whether the first tap read the pocket."""
    beliefs = RunBeliefs.of(run, filter_config(run.config, FILTERS[name]), chunk_instances=chunk_instances)
    parts = []
    for rows in beliefs.chunks:
        trace = beliefs.trace(rows)
        surprise = np.fmax.accumulate(np.asarray(trace.surprise, dtype=float), axis=1)
        escaped = outside_hull(beliefs.model, trace, final_k)
        first = np.asarray(trace.batch.y)[:, 0, 0] < POCKET_CUT_MM
        for k in (1, final_k):
            parts.append(pd.DataFrame({"filter": name, "instance_id": trace.batch.instance_id.astype(str),
                                       "repeat": trace.batch.repeat.astype(int), "k": int(k),
                                       "density": surprise[:, k - 1], "escaped_final": escaped,
                                       "first_tap_pocket": first}))
        del trace
    return pd.concat(parts, ignore_index=True)


def summary(rows: pd.DataFrame, boot: dict[str, Any]) -> dict[str, Any]:
    """Per filter: escapes at the final budget, the share of them whose first tap read the pocket, and the density
    surprise's rank AUC (cluster-bootstrap triple) at the first and final budget, from the stored rows."""
    out: dict[str, Any] = {}
    for name, part in rows.groupby("filter", sort=False):
        first = part[part["k"] == part["k"].min()]
        y = first["escaped_final"].to_numpy(bool)
        out[f"{name}.n_escaped"] = int(y.sum())
        out[f"{name}.first_tap_pocket.escaped"] = float(first["first_tap_pocket"].to_numpy(bool)[y].mean()) if y.any() \
            else float("nan")
        for k, at in part.groupby("k"):
            iv = cluster_bootstrap_auc(at["density"].to_numpy(float), at["escaped_final"].to_numpy(bool),
                                       at["instance_id"].to_numpy(), **boot)
            out[f"{name}.auc_k{int(k)}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    return out


def matches_stored(rows: pd.DataFrame, stored: pd.DataFrame) -> int:
    """1 when the as-run rows equal the stored paper's-schedule test episodes (``schedule_episodes``' rows of that
    run: ``max_surprise`` at each budget, ``escaped`` at the final one) on every trajectory, else 0."""
    mine = rows[rows["filter"] == "as_run"]
    final_k = int(mine["k"].max())
    ref = stored.set_index([stored["instance_id"].astype(str), stored["repeat"].astype(int), stored["k"].astype(int)])
    at = ref.reindex(pd.MultiIndex.from_frame(mine[["instance_id", "repeat", "k"]]))
    last = ref.reindex(pd.MultiIndex.from_arrays([mine["instance_id"], mine["repeat"], np.full(len(mine), final_k)]))
    if at["max_surprise"].isna().any() or last["escaped"].isna().any():
        return 0
    same_s = np.allclose(at["max_surprise"].to_numpy(float), mine["density"].to_numpy(float), rtol=0, atol=1e-9)
    same_e = bool((last["escaped"].astype(bool).to_numpy() == mine["escaped_final"].to_numpy(bool)).all())
    return int(same_s and same_e)


def keys(rows: pd.DataFrame, stored: pd.DataFrame | None, boot: dict[str, Any]) -> dict[str, Any]:
    """Every key of ``explain:results.ex10_surprise`` (the step and ``verify`` both call this); ``stored``: the
    paper's-schedule Split B test episodes as the schedules step stores them."""
    out = {} if stored is None else {"as_run_equals_stored": matches_stored(rows, stored)}
    return {**out, **summary(rows, boot)}


def run(paper_test: LoadedRun, final_k: int, boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys and stored rows for the paper's-schedule Split B test run."""
    rows = pd.concat([filter_rows(paper_test, name, final_k) for name in FILTERS], ignore_index=True)
    episodes = paper_test.episodes
    stored = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    return keys(rows, stored, boot), rows
