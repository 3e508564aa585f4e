"""PyBullet's escape at k = 8 when a trajectory's random taps are drawn without replacement (E62).

Why: the paper's PyBullet escape climbs from 0.055 at k = 1 to 0.167 at k = 8; ours climbs to
0.109 and flattens after k = 4. The paper says only that probes are "uniform random" over the
nine tap positions. Ours draws each tap independently (with replacement), so a k = 8 trajectory
taps about 5.5 distinct positions; drawn without replacement it taps 8 of the 9, and every
further distinct position is another chance to tap the chamfer band the deployed boundary
misreads. The first tap is uniform under either rule, so k = 1 cannot move: a prediction the
data can break.

The run: the engines study's PyBullet instances and repeats, each trajectory's eight positions
the first eight of a seeded permutation of the nine, readings from the analytic scene given our
PyBullet scan's boundary (E45 showed that scene reproduces our PyBullet run's escape at every
budget), beliefs by the deployed model through the ordinary replay. Nothing frozen changes; no
run directory is written (the probes live in memory and in the stored rows).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_mean, paired_bootstrap
from probecommit.runner.build import build_simulator
from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import LoadedRun, load_run, replay_episodes

#: The stored rows (one per trajectory and budget) the summaries come from.
STORED = "ex6_probe_rule.parquet"
#: The engines study's PyBullet run, deployed model.
RUN = "pybullet_B_test_random"
#: Extra entropy of the permutation streams (the experiment's number), so they share no draws with the run's.
STREAM = 62


def without_replacement(n_positions: int, budget: int, seed: int, instance_index: int, repeat: int) -> np.ndarray:
    """Indices of the first ``budget`` positions of a seeded permutation of ``n_positions`` (distinct)."""
    if budget > n_positions:
        raise ValueError(f"cannot draw {budget} distinct taps from {n_positions} positions")
    rng = np.random.default_rng([int(seed), int(instance_index), int(repeat), STREAM])
    return rng.permutation(n_positions)[:budget]


def distinct_taps(probes: pd.DataFrame) -> pd.DataFrame:
    """Per trajectory and budget ``k``, how many distinct positions its first ``k`` taps visited."""
    p = probes.sort_values(["instance_id", "repeat", "j"])
    new = ~p.duplicated(["instance_id", "repeat", "u"])
    return p[["instance_id", "repeat"]].assign(k=p["j"], distinct_taps=new.groupby(
        [p["instance_id"], p["repeat"]]).cumsum().astype(int))


def _scene_config(source: LoadedRun, offset: float) -> Any:
    data = config_data(source.config)
    data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": float(offset),
                         "capture_scale": 1.0}
    return parse_config(data)


def permuted_probes(source: LoadedRun, config: Any) -> pd.DataFrame:
    """Every trajectory of ``source`` tapped at distinct positions, read by ``config``'s simulator."""
    sim = build_simulator(config)
    from probecommit.runner.build import build_model

    grid = np.asarray(build_model(config).probe_grid, dtype=float)
    budget, repeats, rows = int(config.probes.budget), int(config.repeats), []
    for inst in source.instances.itertuples(index=False):
        theta = np.array([inst.true_x_hole, inst.true_c], dtype=float)
        for r in range(repeats):
            order = without_replacement(len(grid), budget, config.seed, inst.instance_index, r)
            rng = np.random.default_rng([int(config.seed), int(inst.instance_index), r, STREAM, 1])
            for j, g in enumerate(order, start=1):
                u = grid[g]
                rows.append((inst.instance_id, r, j, float(u[0]), float(np.asarray(sim.probe(theta, u, rng))[0])))
    return pd.DataFrame(rows, columns=["instance_id", "repeat", "j", "u", "y"])


def _rows(episodes: pd.DataFrame, probes: pd.DataFrame, rule: str) -> pd.DataFrame:
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    rows = rows[["instance_id", "repeat", "k", "escaped"]].assign(escaped=lambda d: d["escaped"].astype(float))
    return rows.merge(distinct_taps(probes), on=["instance_id", "repeat", "k"], how="left").assign(rule=rule)


def run(root: Path, boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame | None]:
    """Keys of ``explain:results.ex6_probe_rule`` and the stored rows (empty when the engines run is absent)."""
    path, scans = root / "engines" / "runs" / RUN, root / "engines" / "results" / "results.json"
    if not (path.is_dir() and scans.is_file()):
        return {}, None
    offset = float(json.loads(scans.read_text())["results"]["scans"]["pybullet"]["boundary"]["delta"])
    source = load_run(path)
    config = _scene_config(source, offset)
    probes = permuted_probes(source, config)
    loaded = LoadedRun(path, config, source.instances, probes=probes, episodes=source.episodes.iloc[0:0],
                       engine_cache=source.engine_cache.iloc[0:0])
    episodes, _ = replay_episodes(loaded, chunk_instances=48)
    rows = pd.concat([_rows(episodes, probes, "without_replacement"),
                      _rows(source.episodes, source.probes, "with_replacement")], ignore_index=True)
    return {"boundary_offset": offset, **summary(rows, boot)}, rows


def summary(rows: pd.DataFrame, boot: dict[str, Any]) -> dict[str, Any]:
    """Escape per rule and budget (cluster-bootstrap triples), the paired final-budget change and the mean
    number of distinct taps by then, from the stored rows (what verify recomputes)."""
    out: dict[str, Any] = {}
    kmax = int(rows["k"].max())
    for rule, part in rows.groupby("rule"):
        for k, at in part.groupby("k"):
            iv = cluster_bootstrap_mean(at["escaped"].to_numpy(float), at["instance_id"].to_numpy(), **boot)
            out[f"{rule}.escape_k{int(k)}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
        out[f"{rule}.distinct_taps_k{kmax}"] = float(part.loc[part["k"] == kmax, "distinct_taps"].mean())
    final = rows[rows["k"] == kmax]
    base, treat = (final[final["rule"] == r].drop(columns=["rule", "distinct_taps"])
                   for r in ("with_replacement", "without_replacement"))
    d = paired_bootstrap(base, treat, "escaped", **boot).difference
    out[f"paired_escape_k{kmax}"] = [float(d.estimate), float(d.lo), float(d.hi)]
    return out
