"""Reproduction targets side by side: independent targets in processes of their own (issue 42, target 4).

``probecommit reproduce all --workers N`` (N >= 2) runs up to N targets at once, each in a
spawned process, a target starting as soon as every target it reads (``Target.needs``) is
done, the longest first. A target's numbers do not depend on what runs beside it: its runs
and replays are computed from the frozen configs and the run directories of the targets it
needs, which are finished before it starts. What a process does not share is the engine
answer store (``tasks.base.shared_engine_answers``): a query two targets both ask is run once
in each of their processes (same answer; more ``engine_calls`` in the record).
"""

from __future__ import annotations

import multiprocessing
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Callable, Sequence

#: Typical wall seconds of each target (a full reproduction on 2 cores, REPRODUCTION.md): the
#: longest ready target starts first, so the long chains start early.
EXPECTED_S = {"breadth": 169.0, "engines": 128.0, "gru": 79.0, "insertion": 73.0, "explain": 36.0, "beyond": 34.0,
              "robot": 4.5, "figures": 3.5, "setup": 1.0, "cost": 1.0}


def run_target(name: str, root: str, quick: bool, workers: int, options: dict[str, Any]) -> tuple[str, float]:
    """One target in this (spawned) process, with its own engine answer store: its results folder and wall seconds."""
    from probecommit.report import paper
    from probecommit.tasks.base import shared_engine_answers

    paper.OPTIONS.clear()
    paper.OPTIONS.update(options)
    start = time.perf_counter()
    with shared_engine_answers():
        folder = paper.TARGETS[name].run(Path(root), quick, paper._noop, workers)
    return str(folder), time.perf_counter() - start


def side_by_side(order: Sequence[str], needs: dict[str, tuple[str, ...]], lanes: int,
                 launch: Callable[[ProcessPoolExecutor, str], Future],
                 progress: Callable[[str, int, int], None],
                 rereads: dict[str, tuple[str, ...]] | None = None) -> dict[str, tuple[str, float]]:
    """Run ``order``'s targets ``lanes`` at a time, each once its ``needs`` (among ``order``) are done.

    Args:
        order: The targets, dependencies first (``paper.resolve``).
        needs: Each target's prerequisites.
        lanes: Targets at once.
        launch: Submits one target to the pool, returning its future (of ``run_target``'s result).
        progress: ``progress(step, done, total)``.
        rereads: Targets that read another's results when they are there (``paper.READS_IF_RUN``)
            without waiting for it: one that finished before what it reads (in ``order``) is run
            again once that is done (its run directories resume; its tables are made again), so
            its results are those of one after the other. What needs it starts after its first run.

    Returns:
        Per target, its results folder and wall seconds (both runs). The first failure is raised
        once the targets already running have finished (their run directories resume).
    """
    rereads = rereads or {}
    waiting = list(order)
    running: dict[Future, str] = {}
    done: dict[str, tuple[str, float]] = {}
    stale: set[str] = set()  # finished before what they read: to run again
    failure: BaseException | None = None
    context = multiprocessing.get_context("spawn")  # no fork of a process whose progress bar runs a thread
    with ProcessPoolExecutor(max_workers=lanes, mp_context=context, max_tasks_per_child=1) as pool:
        while waiting or running or stale:
            ready = [t for t in waiting if all(n in done or n not in order for n in needs.get(t, ()))]
            ready += [t for t in stale if t not in running.values() and all(r in done for r in rereads[t] if r in order)]
            ready.sort(key=lambda t: -EXPECTED_S.get(t, 0.0))
            while failure is None and ready and len(running) < lanes:
                target = ready.pop(0)
                if target in waiting:
                    waiting.remove(target)
                stale.discard(target)
                running[launch(pool, target)] = target
                progress(f"targets side by side (running: {', '.join(sorted(running.values()))})", len(done), len(order))
            if not running:
                break
            finished, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for future in finished:
                target = running.pop(future)
                try:
                    folder, seconds = future.result()
                except BaseException as exc:  # noqa: BLE001 - re-raised after the others finish
                    failure = failure or exc
                    continue
                done[target] = (folder, seconds + (done[target][1] if target in done else 0.0))
                if any(r in order and r not in done for r in rereads.get(target, ())):
                    stale.add(target)
                progress("targets side by side", len(done), len(order))
    if failure is not None:
        raise failure
    return done
