"""PyBullet's escape when its tap boundary is drawn afresh at every tap (E87).

Why: the paper's PyBullet escape climbs to 0.167 at k = 8; ours to 0.109. E45 gave the analytic
scene the paper's PyBullet boundary (hg + 0.929 mm) as one fixed line and E62 changed the tap
draw; neither reached it. Our PyBullet reads the same boundary at every tap and truth (scan SD
0.001 mm), while the paper's PyBullet is the engine whose contact properties it reports spread
widely (capture window SD 0.69 of the ratio over 24 truths; ours 0.0002), and its Table VI keeps
some escape with the MuJoCo offset and with PyBullet's own scan (0.023, 0.031), which a fixed
boundary at or inside the model's cannot give (ours: none). If the boundary moves from tap to tap,
two taps near it can contradict each other and no deterministic model explains both.

The run: each engines-study PyBullet trajectory of all three variants (their own taps and noise)
is re-read by the analytic rule ``|u - x| < hg(c) + m + s z`` (``m`` the paper's PyBullet offset,
``z`` one standard normal per tap, seeded, the same ``z`` for every ``s`` and variant), keeping the
run's noise residual, and the belief is replayed under the variant's model; escape is the truth
outside the full particle hull at each budget. ``s`` runs over the grid declared in
docs/decisions.md. No run directory is written; the rows are stored.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_mean
from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import LoadedRun, RunBeliefs, load_run
from probecommit.tasks.insertion.model import half_gap

#: The stored rows (variant, s, trajectory, budget, escaped) the summaries come from.
STORED = "ex10_boundary_noise.parquet"
#: The engines study's PyBullet runs, by variant.
RUNS = {"deployed": "pybullet_B_test_random", "mj_offset": "pybullet_B_test_random_mj_offset",
        "own_scan": "pybullet_B_test_random_own_scan"}
#: Extra entropy of the per-tap boundary draws (the experiment's number): no draw shared with the runs.
STREAM = 87
#: A reading below this (mm) is the pocket floor (-15 mm), above it the plate top (0 mm).
POCKET_CUT_MM = -7.5
POCKET_MM, TOP_MM = -15.0, 0.0


def s_label(s: float) -> str:
    """Key fragment of a boundary SD in tenths of a millimetre (``0.3`` -> ``s03``): no dot inside a key."""
    return f"s{int(round(float(s) * 10)):02d}"


def tap_draws(probes: pd.DataFrame, instances: pd.DataFrame, seed: int) -> np.ndarray:
    """One standard normal per stored tap, seeded by (seed, instance, repeat, STREAM) and indexed by the tap's
    ``j``, so every variant and every ``s`` reads the same draw at the same tap."""
    index = instances.set_index("instance_id")["instance_index"]
    out = np.empty(len(probes))
    for (iid, rep), rows in probes.groupby(["instance_id", "repeat"], sort=False).indices.items():
        j = probes["j"].to_numpy()[rows]
        z = np.random.default_rng([int(seed), int(index[iid]), int(rep), STREAM]).standard_normal(int(j.max()))
        out[rows] = z[j - 1]
    return out


def reread(probes: pd.DataFrame, instances: pd.DataFrame, z: np.ndarray, mean_offset: float,
           s: float) -> pd.DataFrame:
    """``probes`` with each reading's level re-decided against the boundary ``hg(c) + mean_offset + s z`` and its
    noise residual (reading minus its stored level) kept."""
    truth = instances.set_index("instance_id").loc[probes["instance_id"], ["true_x_hole", "true_c"]].to_numpy(float)
    u, y = probes["u"].to_numpy(float), probes["y"].to_numpy(float)
    pocket = np.abs(u - truth[:, 0]) < half_gap(truth[:, 1]) + mean_offset + s * np.asarray(z, dtype=float)
    old = np.where(y < POCKET_CUT_MM, POCKET_MM, TOP_MM)
    return probes.assign(y=y - old + np.where(pocket, POCKET_MM, TOP_MM))


def outside_hull(model: Any, trace: Any, k: int) -> np.ndarray:
    """``[E]`` whether each truth lies outside the full particle hull of its belief at budget ``k`` (the runner's
    escape: every particle, whatever its weight)."""
    truth = np.asarray(model.decision(trace.batch.truths[:, None, :]), dtype=float).reshape(-1)
    z = np.asarray(model.decision(trace.states[k].particles), dtype=float)
    return (truth < z.min(axis=1)) | (truth > z.max(axis=1))


def hull_escape(loaded: LoadedRun, chunk_instances: int = 48) -> pd.DataFrame:
    """Per trajectory and budget, whether the truth lies outside the full particle hull (the runner's escape)."""
    beliefs = RunBeliefs.of(loaded, chunk_instances=chunk_instances)
    parts = []
    for rows in beliefs.chunks:
        trace = beliefs.trace(rows)
        for k in trace.budgets:
            parts.append(pd.DataFrame({"instance_id": trace.batch.instance_id.astype(str),
                                       "repeat": trace.batch.repeat.astype(int), "k": int(k),
                                       "escaped": outside_hull(beliefs.model, trace, k)}))
        del trace
    return pd.concat(parts, ignore_index=True)


def _analytic(source: LoadedRun, probes: pd.DataFrame) -> LoadedRun:
    data = config_data(source.config)  # the model and filter as run; the scene is never queried
    data["simulator"] = {**data["simulator"], "engine": "analytic"}
    return LoadedRun(source.path, parse_config(data), source.instances, probes=probes,
                     episodes=source.episodes.iloc[0:0], engine_cache=source.engine_cache.iloc[0:0])


def variant_rows(source: LoadedRun, variant: str, mean_offset: float, grid: Sequence[float]) -> pd.DataFrame:
    """Stored rows of one variant: the escape as run (``s`` NaN, from the stored readings) and at each ``s``."""
    z = tap_draws(source.probes, source.instances, int(source.config.seed))
    parts = [hull_escape(_analytic(source, source.probes)).assign(s=np.nan)]
    for s in grid:
        parts.append(hull_escape(_analytic(source, reread(source.probes, source.instances, z, mean_offset, s)))
                     .assign(s=float(s)))
    return pd.concat(parts, ignore_index=True).assign(variant=variant)


def summary(rows: pd.DataFrame, boot: dict[str, Any]) -> dict[str, Any]:
    """Escape at the first and last budget (cluster-bootstrap triples) per variant and ``s``, and the escape as
    run at the last budget, from the stored rows (what verify recomputes)."""
    out: dict[str, Any] = {}
    kmin, kmax = int(rows["k"].min()), int(rows["k"].max())
    for (variant, s), part in rows.groupby(["variant", rows["s"].fillna(-1.0)], sort=False):
        name = "as_run" if s < 0 else s_label(s)
        for k in (kmin, kmax):
            at = part[part["k"] == k]
            iv = cluster_bootstrap_mean(at["escaped"].to_numpy(float), at["instance_id"].to_numpy(), **boot)
            out[f"{variant}.{name}.escape_k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    return out


def matches_stored(rows: pd.DataFrame, episodes: pd.DataFrame) -> int:
    """1 when the as-run rows' escape equals the stored run's (``episodes``: one variant's Probe-Robust rows) on
    every trajectory and budget, else 0."""
    mine = rows[rows["s"].isna()].set_index(["instance_id", "repeat", "k"])["escaped"]
    ok = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    theirs = ok.set_index([ok["instance_id"].astype(str), ok["repeat"].astype(int), ok["k"].astype(int)])["escaped"]
    theirs = theirs.reindex(mine.index)
    return int(len(mine) > 0 and theirs.notna().all() and bool((theirs.astype(bool).to_numpy() == mine.to_numpy()).all()))


def keys(rows: pd.DataFrame, engine_episodes: pd.DataFrame | None, boot: dict[str, Any]) -> dict[str, Any]:
    """Every key of ``explain:results.ex10_boundary`` from the stored rows and the engines study's PyBullet
    episodes (``engine``, ``variant`` columns, as ``engines/engine_episodes.parquet``): the explain step and
    ``verify`` both call this."""
    out: dict[str, Any] = {}
    if engine_episodes is not None:
        pb = engine_episodes[engine_episodes["engine"] == "pybullet"]
        for variant in rows["variant"].unique():
            out[f"{variant}.as_run_equals_stored"] = matches_stored(rows[rows["variant"] == variant],
                                                                    pb[pb["variant"] == variant])
    return {**out, **summary(rows, boot)}


def run(root: Path, grid: Sequence[float], mean_offset: float,
        boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame | None]:
    """Keys of ``explain:results.ex10_boundary`` and the stored rows (none when the engines runs are absent)."""
    paths = {v: root / "engines" / "runs" / name for v, name in RUNS.items()}
    if not all(p.is_dir() for p in paths.values()):
        return {}, None
    parts, episodes = [], []
    for variant, path in paths.items():
        source = load_run(path)
        parts.append(variant_rows(source, variant, mean_offset, grid))
        episodes.append(source.episodes.assign(engine="pybullet", variant=variant))
    rows = pd.concat(parts, ignore_index=True)
    return keys(rows, pd.concat(episodes, ignore_index=True), boot), rows
