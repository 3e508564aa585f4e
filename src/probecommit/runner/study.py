"""Turn a study config into a run directory: units, backends, resume.

A *unit* is a fixed group of ``unit_instances`` instances with all their repeats.
Units are independent (every random draw is keyed by instance and repeat), so they
run in any order, in local processes or on Ray, and a killed run resumes by
skipping the units whose shards are already on disk. Results are bit-identical
whatever the backend or the number of workers.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd

from probecommit.runner.build import build_filter, build_model, build_simulator
from probecommit.runner.config import StudyConfig, dump_config, parse_config
from probecommit.runner.inference import blind_bayes_action, build_trace, commit, failed_episode_rows, rollout
from probecommit.runner.instances import draw_instances
from probecommit.store.rundir import RunDir


@dataclass
class StudyResult:
    run_dir: Path
    manifest: dict[str, Any]
    episodes: pd.DataFrame


def unit_names(n_instances: int, unit_instances: int) -> list[tuple[str, slice]]:
    return [
        (f"unit-{i // unit_instances:05d}", slice(i, min(i + unit_instances, n_instances)))
        for i in range(0, n_instances, unit_instances)
    ]


def run_unit(config_data: dict, instances: pd.DataFrame, unit: str, out: str) -> dict[str, Any]:
    """Run one unit end to end and write its shards; returns its stats.

    Top-level and argument-only so process pools and Ray can ship it.
    """
    start = time.perf_counter()
    config = parse_config(config_data)
    model = build_model(config.model)
    pfilter = build_filter(model, config.belief)
    simulator = build_simulator(config.simulator)
    schedule = config.probes.schedule
    batch = rollout(
        instances, config.repeats, schedule, config.probes.budget, model.probe_grid, simulator,
        config.seed, model.latent_names,
    )
    if config.simulator.execute_all_aims:
        for theta in batch.truths[:: config.repeats]:
            for aim in model.action_grid:
                try:
                    simulator.execute(theta, float(aim))
                except Exception:  # noqa: BLE001 - recorded when an episode commits there
                    pass
    trace = build_trace(pfilter, batch, config.seed, config.probes.commit_budgets)
    blind = blind_bayes_action(model, config.seed, config.blind_prior_samples) if "blind_bayes" in config.methods else None
    episodes = commit(trace, model, simulator, thresholds=config.belief.nu, methods=config.methods, blind=blind)
    failed = failed_episode_rows(batch, model.variant)
    if len(failed):
        episodes = pd.concat([episodes, failed], ignore_index=True)
    stats = {
        "unit": unit,
        "engine_calls": dict(simulator.engine_calls),
        "engine_s": simulator.engine_seconds,
        "wall_s": time.perf_counter() - start,
        "episodes": int(batch.n_episodes),
        "failed_trajectories": int(np.sum(batch.status != "ok")),
        "failed_rows": int(np.sum(episodes["status"] != "ok")),
    }
    RunDir(out).write_unit(
        unit,
        {
            "instances": instances.reset_index(drop=True),
            "probes": batch.probes_frame(),
            "engine_cache": pd.DataFrame(simulator.cache_records(), columns=["engine", "query", "x_hole", "c", "arg", "value"]),
            "episodes": episodes,
        },
        stats,
    )
    return stats


def _run_serial(jobs, progress):
    for job in jobs:
        run_unit(*job)
        progress()


def _run_processes(jobs, workers: int, progress):
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # "spawn": engines hold native state that must not be forked.
    with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as pool:
        for fut in as_completed([pool.submit(run_unit, *job) for job in jobs]):
            fut.result()
            progress()


def _run_ray(jobs, address: str, progress):
    from probecommit.engines import require

    ray = require("ray")
    started_here = not ray.is_initialized()
    if started_here:
        if address == "local":
            ray.init(num_cpus=None, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, include_dashboard=False, log_to_driver=False)
    try:
        remote = ray.remote(run_unit)
        pending = [remote.remote(*job) for job in jobs]
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            ray.get(done[0])
            progress()
    finally:
        if started_here:
            ray.shutdown()


def run_study(
    config: StudyConfig,
    out: str | Path,
    workers: int = 1,
    ray_address: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> StudyResult:
    """Run (or resume) a study into ``out``.

    Args:
        config: The validated study config.
        out: Run directory; an existing one is resumed only if its config matches.
        workers: Local worker processes (1 = in this process).
        ray_address: Run units on Ray instead: ``"auto"``, ``"local"`` or ``host:port``.
        progress: Called as ``progress(done, total)`` after each unit.
    """
    start = time.perf_counter()
    run = RunDir(out)
    run.prepare(dump_config(config))
    model = build_model(config.model)
    instances = draw_instances(config, model.latent_names)
    units = unit_names(len(instances), config.unit_instances)
    config_data = config.model_dump(mode="json")
    jobs = [(config_data, instances.iloc[sl], name, str(run.path)) for name, sl in units if not run.unit_done(name)]
    done = len(units) - len(jobs)
    counter = {"done": done}

    def tick() -> None:
        counter["done"] += 1
        if progress:
            progress(counter["done"], len(units))

    if progress:
        progress(done, len(units))
    if ray_address:
        _run_ray(jobs, ray_address, tick)
    elif workers > 1 and len(jobs) > 1:
        _run_processes(jobs, workers, tick)
    else:
        _run_serial(jobs, tick)
    stats = [run.unit_stats(name) for name, _ in units]
    calls: dict[str, int] = {}
    for s in stats:
        for key, value in s["engine_calls"].items():
            calls[key] = calls.get(key, 0) + value
    manifest = run.finalize(
        [name for name, _ in units],
        {
            "study": config.name,
            "engine": config.simulator.engine,
            "engine_calls": calls,
            "timing": {
                "engine_s": float(sum(s["engine_s"] for s in stats)),
                "units_wall_s": float(sum(s["wall_s"] for s in stats)),
                "this_invocation_wall_s": time.perf_counter() - start,
            },
            "episodes": int(sum(s["episodes"] for s in stats)),
            "failed_trajectories": int(sum(s["failed_trajectories"] for s in stats)),
            "failed_rows": int(sum(s["failed_rows"] for s in stats)),
            "resumed_units": done,
        },
    )
    return StudyResult(run.path, manifest, pd.read_parquet(run.table_path("episodes")))
