"""The few new runs the explanations need, each a controlled change of one stored run.

* the cover schedule the paper froze, on the Split B calibration and test instances (same
  split names, hence the same truths and the same tap-noise streams as our schedule's runs,
  so the two schedules are compared on identical instances);
* Split B's random-probe calibration run replayed under the corrected boundary (the
  corrected random-probe simultaneous threshold);
* the analytic insertion scene with the two PhysX scene properties the paper measured (tap
  boundary and capture window), random probes on Split B test, replayed with the MuJoCo
  offset and with the scene's own boundary: does the paper's capture window alone give its
  PhysX column?
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import LoadedRun, load_run, replay_run
from probecommit.runner.study import run_study
from probecommit.store.rundir import RunDir
from probecommit.studies.protocol import Protocol


def _run(config: Any, path: Path, workers: int) -> LoadedRun:
    run_study(config, path, workers=workers, threads=1)
    return load_run(path)


def _replay(source: Path, path: Path, overrides: dict) -> LoadedRun:
    if not RunDir(path).is_complete():
        replay_run(source, path, overrides, chunk_instances=48)
    return load_run(path)


def schedule_runs(protocol: Protocol, schedule: list[float], runs: Path, workers: int = 1) -> dict[str, LoadedRun]:
    """Split B calibration and test, and Split A, under another cover schedule (probe executor only)."""
    p = protocol.model_copy(update={"cover_schedule": [float(u) for u in schedule]})
    out = {}
    for part in ("cal", "test"):
        config = p.run_config(f"B_{part}_cover_paper_schedule", "B", f"B_{part}_cover", "cover")
        out[part] = _run(config, runs / f"B_{part}_cover_paper_schedule", workers)
    out["A"] = _run(p.run_config("A_cover_paper_schedule", "A", "A", "cover"), runs / "A_cover_paper_schedule", workers)
    return out


def testc_schedule_runs(protocol: Protocol, schedule: list[float], runs: Path, workers: int = 1) -> tuple[LoadedRun, LoadedRun]:
    """Test C's cover run under another cover schedule (probe executor only; split name ``C_cover``, hence Test C's
    instances and tap-noise streams) and its replay under the corrected boundary, as the insertion study's ``C_cover``
    and ``C_cover_corrected``."""
    p = protocol.model_copy(update={"cover_schedule": [float(u) for u in schedule]})
    old = _run(p.run_config("C_cover_paper_schedule", "C", "C_cover", "cover"), runs / "C_cover_paper_schedule", workers)
    return old, corrected_replay(old.path, runs, protocol.delta)


def corrected_replay(source: Path, runs: Path, delta: float) -> LoadedRun:
    """A stored run's probes re-inferred under the corrected boundary ``hg + delta``."""
    return _replay(source, runs / f"{source.name}_corrected", {"model": {"boundary": "corrected", "delta": float(delta)}})


def emulated_engine_runs(protocol: Protocol, runs: Path, boundary_offset: float, capture_scale: float,
                         workers: int = 1) -> dict[str, LoadedRun]:
    """The analytic scene with a given tap boundary and capture window, under the three tap models.

    The instances and probe streams are the engines study's (split ``B_test``, random probes).
    """
    base = protocol.run_config("emulated_B_test_random", "B", "B_test", "random")
    data = config_data(base)
    data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": float(boundary_offset),
                         "capture_scale": float(capture_scale)}
    deployed = _run(parse_config(data), runs / "emulated_B_test_random", workers)
    out = {"deployed": deployed}
    for variant, delta in (("mj_offset", protocol.delta), ("own_scan", boundary_offset)):
        out[variant] = _replay(deployed.path, runs / f"emulated_B_test_random_{variant}",
                               {"model": {"boundary": "corrected", "delta": float(delta)}})
    return out


def fresh_draws(protocol: Protocol, runs: Path, count: int, workers: int = 1) -> list[tuple[str, LoadedRun, LoadedRun]]:
    """``count`` fresh 96-instance draws of Split B's generator, random probes, on the analytic scene
    whose tap boundary is the MuJoCo scene's (hg + delta), each with its corrected-model replay.

    Split names ``draw_<i>`` give disjoint instance streams; ``B_test_random`` first reproduces
    the MuJoCo run's instances and probe streams (the check that the analytic scene stands in).

    Returns:
        ``(split, deployed run, corrected replay)`` per draw, the check first.
    """
    out = []
    for split in ["B_test_random", *[f"draw_{i:02d}" for i in range(count)]]:
        data = config_data(protocol.run_config(f"analytic_{split}", "B", split, "random"))
        data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": float(protocol.delta),
                             "capture_scale": 1.0}
        deployed = _run(parse_config(data), runs / f"analytic_{split}", workers)
        corrected = _replay(deployed.path, runs / f"analytic_{split}_corrected",
                            {"model": {"boundary": "corrected", "delta": float(protocol.delta)}})
        out.append((split, deployed, corrected))
    return out
