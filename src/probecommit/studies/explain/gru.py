"""Why the GRU's equivalence interval is wider than the paper's, and whether its training repeats.

From the GRU study's per-episode misses (``gru_episodes.parquet``): the spread of the paired
difference across instances (what the cluster bootstrap measures), the spread across seeds
(which the published interval averages away), a bootstrap over both, and the power the
+-0.020 m margin had. Then one seed is trained again from scratch, with the frozen thread
count and with another, and its parameters compared with the study's checkpoint: the
tolerance of a rerun, measured.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import percentile_interval, resample_counts


def difference_spread(episodes: pd.DataFrame, resamples: int, seed: int) -> dict[str, Any]:
    """Instance and seed components of the GRU - pipeline difference, and a two-way bootstrap.

    Args:
        episodes: ``instance_id``, ``realized`` (pipeline) and ``gru_seed_<s>`` columns.
    """
    seeds = [c for c in episodes.columns if c.startswith("gru_seed_")]
    per_seed = episodes[seeds].to_numpy(float) - episodes[["realized"]].to_numpy(float)  # [E, S]
    labels, inverse = np.unique(episodes["instance_id"].to_numpy().astype(str), return_inverse=True)
    m, s = labels.size, len(seeds)
    n = np.bincount(inverse, minlength=m).astype(float)
    cluster = np.stack([np.bincount(inverse, weights=per_seed[:, j], minlength=m) for j in range(s)], axis=1)  # sums [M, S]
    cluster_mean = cluster.sum(axis=1) / s / n
    seed_estimates = cluster.sum(axis=0) / n.sum()
    counts = resample_counts(m, resamples, seed)
    rng = np.random.default_rng(seed + 1)
    pick = rng.integers(0, s, size=(resamples, s))
    seed_w = np.stack([np.bincount(row, minlength=s) for row in pick]).astype(float) / s  # [B, S]
    num = np.einsum("bm,ms,bs->b", counts, cluster, seed_w)
    two_way = num / (counts @ n)
    return {"instances": int(m), "seeds": int(s),
            "instance_sd_of_difference": float(np.std(cluster_mean, ddof=1)),
            "se_instances": float(np.std(cluster_mean, ddof=1) / np.sqrt(m)),
            "seed_sd_of_difference": float(np.std(seed_estimates, ddof=1)),
            "se_seeds": float(np.std(seed_estimates, ddof=1) / np.sqrt(s)),
            "two_way_interval": [float(seed_estimates.mean()), *percentile_interval(two_way)]}


def retrain_tolerance(study_dir: Path, pipeline_run: Path, scratch: Path, quick: bool) -> dict[str, Any]:
    """Train seed 0 again from scratch (frozen threads, then 2 threads) and compare parameters."""
    from probecommit.baselines.gru import TrainingConfig, make_training_set, train
    from probecommit.runner.build import build_model
    from probecommit.runner.replay import load_run
    from probecommit.engines import require
    from probecommit.studies.gru import load_gru_config

    torch = require("torch")

    cfg = load_gru_config()
    training = dict(cfg["training"])
    if quick:
        training.update(steps=cfg["quick"]["steps"], samples=cfg["quick"]["samples"])
    loaded = load_run(pipeline_run)
    model = build_model(loaded.config)
    contexts = np.array(loaded.config.instances.contexts, dtype=float)
    out: dict[str, Any] = {}
    checkpoint = study_dir / "checkpoints" / "seed-00.pt"
    reference = torch.load(checkpoint, weights_only=True) if checkpoint.is_file() else None
    data = make_training_set(model, contexts, TrainingConfig(budget=cfg["budget"], **training), cfg["data_seed"])
    states = {}
    for threads in (int(training["threads"]), 2):
        tcfg = TrainingConfig(budget=cfg["budget"], **{**training, "threads": threads})
        states[threads], _ = train(data, model, tcfg, 0, None)
    frozen = int(training["threads"])

    def max_diff(a: dict, b: dict) -> float:
        return float(max((a[k].double() - b[k].double()).abs().max().item() for k in a))

    if reference is not None:
        out["retrain_vs_study_max_abs_param_diff"] = max_diff(states[frozen], reference)
    out["threads_2_vs_frozen_max_abs_param_diff"] = max_diff(states[2], states[frozen])
    torch.set_num_threads(frozen)
    return out


def summary_keys(r: dict[str, Any], per_episode: pd.DataFrame | None, boot: dict[str, int],
                 paper_interval: tuple[float, float]) -> dict[str, Any]:
    """``explain:results.gru`` but the retrained seed's tolerance: the GRU study's difference and its implied
    SE against the paper's, the power of the equivalence margin, and (with the per-episode misses) the spread
    over instances and seeds. ``r`` is the GRU study's results (``studies.gru.summarize_gru``: its results.json
    in the explain step, recomputed from ``gru_episodes.parquet`` in verify)."""
    from probecommit.studies.explain.stats import equivalence_power, interval_se

    est, lo, hi = r["gru_minus_pipeline"]
    margin = float(r["equivalence_margin"])
    se = interval_se(lo, hi)
    out: dict[str, Any] = {"available": 1, "difference": [est, lo, hi], "se_implied": se,
                           "seed_miss_sd": float(r["seed_miss_sd"]),
                           "seed_sd_of_mean": float(r["seed_miss_sd"]) / np.sqrt(max(int(r["seeds"]), 1))}
    for name, delta in (("power_at_zero", 0.0), ("power_at_estimate", est)):
        out[name] = equivalence_power(se, delta, margin)
    paper_se = interval_se(*paper_interval)
    out["se_paper_implied"] = paper_se
    out["se_ratio"] = se / paper_se
    out["power_at_estimate_with_paper_se"] = equivalence_power(paper_se, est, margin)
    if per_episode is not None:
        spread = difference_spread(per_episode, **boot)
        out.update(spread)
        out["instances_for_paper_se"] = float(spread["instances"] * (se / paper_se) ** 2)
        out["power_at_estimate_two_way"] = equivalence_power(interval_se(*spread["two_way_interval"][1:]), est, margin)
    return out
