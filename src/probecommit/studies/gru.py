"""The learned baseline: a GRU against the pipeline on MuJoCo 2-D pushing (``reproduce gru``).

Reads the pipeline's push2d run (its Probe-Robust(5) episodes and stored probe
histories), trains one GRU per seed (``baselines/gru.py``, checkpointed so an interrupted
run resumes per seed), commits each policy on the same histories, scores the commits in
MuJoCo (the run's engine cache plus any new query), and tests equivalence: the paired
difference GRU - pipeline in mean miss, with a cluster bootstrap over instances (repeats
kept together), must lie inside the pre-registered margin. The per-episode GRU miss is
the mean over seeds, so the interval is over instances, not over seeds; the seeds' spread
is reported beside it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd

from probecommit.audit.stats import paired_bootstrap
from probecommit.baselines.gru import TrainingConfig, act, encode_history, equivalent, feature_scales, make_training_set, train_or_resume
from probecommit.runner.build import build_model
from probecommit.runner.inference import instance_arrays
from probecommit.runner.replay import load_run, probe_batch, simulator_for_run
from probecommit.studies.paper_values import PRINTED as PAPER_GRU
from probecommit.store.safefile import write_text, write_with
from probecommit.store.yamlsafe import load_yaml

CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "paper"


def load_gru_config(path: str | Path | None = None) -> dict[str, Any]:
    return load_yaml(Path(path or CONFIG_DIR / "gru.yaml").read_bytes(), str(path or CONFIG_DIR / "gru.yaml"))


def train_seed(checkpoints: str, model: Any, contexts: np.ndarray, tcfg: TrainingConfig, data_seed: int,
               seed: int) -> int:
    """Train seed ``seed`` into ``checkpoints`` (in a worker process; the loop below reads it back)."""
    data = make_training_set(model, contexts, tcfg, data_seed + seed)
    train_or_resume(Path(checkpoints), data, model, tcfg, seed)
    return seed


def train_in_parallel(checkpoints: Path, model: Any, contexts: np.ndarray, tcfg: TrainingConfig, data_seed: int,
                      seeds: int, workers: int, step: Callable[[str, int, int], None]) -> None:
    """Train the seeds ``workers`` at a time in spawned processes, each checkpointed as the one-by-one
    loop would (one torch thread, seeded, deterministic: the same weights), so that loop only reads them."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(workers, seeds), mp_context=context) as pool:
        futures = [pool.submit(train_seed, str(checkpoints), model, contexts, tcfg, data_seed, seed)
                   for seed in range(seeds)]
        for done, future in enumerate(as_completed(futures), start=1):
            future.result()
            step(f"gru: training {min(workers, seeds)} seeds at a time", done, seeds)


def reproduce_gru(out: str | Path, pipeline_run: str | Path, quick: bool = False,
                  progress: Callable[[str, int, int], None] | None = None, config_path: str | Path | None = None,
                  workers: int = 1) -> dict:
    """Train, evaluate and test equivalence; writes ``out/results.json`` and ``out/table_gru.md``.

    With ``workers`` > 1 the seeds are trained that many at a time in processes of their own
    (identical weights: each seed's training is seeded and single-threaded)."""
    out = Path(out)
    step = progress or (lambda *a: None)
    cfg = load_gru_config(config_path)
    training = dict(cfg["training"])
    seeds = cfg["seeds"]
    if quick:
        training.update(steps=cfg["quick"]["steps"], samples=cfg["quick"]["samples"])
        seeds = cfg["quick"]["seeds"]
    tcfg = TrainingConfig(budget=cfg["budget"], **training)
    loaded = load_run(pipeline_run)
    model = build_model(loaded.config)
    contexts = np.array(loaded.config.instances.contexts, dtype=float)
    batch = probe_batch(loaded, model)
    k = cfg["budget"]
    x = encode_history(batch.u[:, :k], batch.y[:, :k], batch.context, *feature_scales(model))
    simulator = simulator_for_run(loaded)
    if workers > 1 and seeds > 1:
        train_in_parallel(out / "checkpoints", model, contexts, tcfg, cfg["data_seed"], seeds, workers, step)
    per_seed, meta = [], []
    for i, seed in enumerate(range(seeds)):
        data = make_training_set(model, contexts, tcfg, cfg["data_seed"] + seed)
        state, info = train_or_resume(out / "checkpoints", data, model, tcfg, seed,
                                      progress=lambda d, t, s=seed: step(f"gru: training seed {s}", d, t))
        meta.append(info)
        index = act(state, x, model, tcfg)
        actions = np.asarray(model.action_grid)[index]
        miss = np.array([simulator.execute(batch.truths[e], actions[e], batch.context[e])["realized"]
                         for e in range(batch.n_episodes)])
        per_seed.append(miss)
        step("gru: seeds", i + 1, seeds)
    per_seed = np.array(per_seed)
    episodes = loaded.episodes
    pipe = episodes[(episodes["method"] == "probe_robust") & (episodes["k"] == k) & (episodes["status"] == "ok")]
    keys = pd.DataFrame({"instance_id": batch.instance_id.astype(str), "repeat": batch.repeat, "k": k})
    pipe = keys.merge(pipe[["instance_id", "repeat", "realized"]], on=["instance_id", "repeat"], how="left")
    # Per episode: the pipeline's miss and each seed's GRU miss (what `reproduce explain` reads
    # to split the interval's width into instance and seed variation, and verify recomputes the table from).
    per_episode = pipe.assign(**{f"gru_seed_{s}": per_seed[s] for s in range(len(per_seed))})
    results = {**summarize_gru(per_episode, cfg["bootstrap"], cfg["equivalence_margin"]),
               "training_loss_last_mean": float(np.mean([m["loss_last"] for m in meta])),
               "bootstrap": dict(cfg["bootstrap"])}
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "results.json", json.dumps({"results": results}, indent=1))
    write_with(out / "gru_episodes.parquet", per_episode.to_parquet)
    write_text(out / "table_gru.md", gru_markdown(results))
    return results


def summarize_gru(per_episode: pd.DataFrame, bootstrap: dict[str, Any], margin: float) -> dict[str, Any]:
    """The GRU table's numbers from the per-episode misses (``gru_episodes.parquet``): one function for
    the study and for ``probecommit verify``. The GRU's miss per episode is its mean over the seeds."""
    seeds = sorted((c for c in per_episode.columns if c.startswith("gru_seed_")), key=lambda c: int(c.rsplit("_", 1)[1]))
    per_seed = per_episode[seeds].to_numpy(float).T
    keys = per_episode[["instance_id", "repeat", "k"]].reset_index(drop=True)
    pipe = keys.assign(realized=per_episode["realized"].to_numpy(float))
    gru = keys.assign(realized=per_seed.mean(axis=0))
    diff = paired_bootstrap(pipe, gru, "realized", **bootstrap).difference
    difference = [diff.estimate, diff.lo, diff.hi]
    seed_means = per_seed.mean(axis=1)
    return {
        "pipeline_miss": float(pipe["realized"].mean()),
        "gru_miss": float(gru["realized"].mean()),
        "gru_minus_pipeline": difference,
        "equivalence_margin": margin,
        "equivalent": equivalent(tuple(difference), margin),
        "seeds": len(seeds),
        "seed_miss_mean": float(seed_means.mean()),
        "seed_miss_sd": float(seed_means.std(ddof=1)) if len(seeds) > 1 else 0.0,
        "seed_miss_min": float(seed_means.min()), "seed_miss_max": float(seed_means.max()),
        "episodes": int(len(per_episode)),
        "k": int(keys["k"].iloc[0]),
    }


def gru_markdown(results: dict) -> str:
    """The GRU table from its results (verify renders it again from the stored results.json)."""
    k, seeds, difference, margin = results["k"], results["seeds"], results["gru_minus_pipeline"], results["equivalence_margin"]
    return ("| quantity | paper | ours [95% CI] |\n|---|---|---|\n"
            f"| pipeline mean miss, Probe-Robust({k}) (m) | {PAPER_GRU['T10-gru.pipeline']} | {results['pipeline_miss']:.3f} |\n"
            f"| GRU mean miss over {seeds} seeds (m) | {PAPER_GRU['T10-gru.gru']} | {results['gru_miss']:.3f} |\n"
            f"| GRU - pipeline (m) | {PAPER_GRU['T10-gru.diff']} [{PAPER_GRU['T10-gru.diff_lo']}, {PAPER_GRU['T10-gru.diff_hi']}] "
            f"| {difference[0]:+.3f} [{difference[1]:+.3f}, {difference[2]:+.3f}] |\n"
            f"| inside the +-{margin:.3f} m margin | yes | {'yes' if results['equivalent'] else 'no'} |\n")
