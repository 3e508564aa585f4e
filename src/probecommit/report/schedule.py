"""Reproduction targets side by side: independent targets in processes of their own (issue 42, target 4).

``probecommit reproduce all --workers N`` (N >= 2) runs up to N targets at once, each in a
spawned process, a target starting as soon as every target it reads (``Target.needs``) is
done, the longest first. A target's numbers do not depend on what runs beside it: its runs
and replays are computed from the frozen configs and the run directories of the targets it
needs, which are finished before it starts. What a process does not share is the engine
answer store (``tasks.base.shared_engine_answers``): a query two targets both ask is run once
in each of their processes (same answer; more ``engine_calls`` in the record).

Two things keep the wall time near the work divided by the lanes rather than the longest chain
of needs: a target whose needs are read only in its last steps (``LATE_NEEDS``) starts once its
other needs are done and waits for those where it reads them (``wait_for``); and of the ready
targets, the one with the longest expected chain after it starts first (``chain_seconds``).
"""

from __future__ import annotations

import json
import multiprocessing
import os
import shutil
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Callable, Sequence

#: Typical wall seconds of each target (a full ``reproduce all --workers 2`` on a loaded 2-core machine,
#: its reproduction.json): of the ready targets, the one with the longest chain after it starts first.
EXPECTED_S = {"explain": 587.0, "breadth": 258.0, "engines": 215.0, "gru": 139.0, "insertion": 105.0, "beyond": 88.0,
              "robot": 8.0, "figures": 7.0, "setup": 3.0, "cost": 2.0}
#: Needs a target reads only in its later steps (``Target.needs`` still runs them first one after the
#: other). Side by side it starts once its other needs are done and waits for these where it first
#: reads them: explain reads the engines study after its own runs, and the GRU study (and the breadth
#: study's push2d run it trained on) and the breadth and cost studies' results in its last steps.
LATE_NEEDS: dict[str, tuple[str, ...]] = {"explain": ("engines", "breadth", "gru", "cost")}
#: The share of a target's expected seconds after it reads its late needs (explain: its GRU and
#: Table II steps), for ``chain_seconds``.
LATE_SHARE = 0.15
#: The folder under the reproduction's root where side by side says which targets are done.
MARKERS = ".side_by_side"


def wait_for(markers: str, names: Sequence[str], poll_s: float = 0.5) -> None:
    """Return once every target in ``names`` is done (``<markers>/<name>.done``), in a target's process.

    Raises:
        RuntimeError: the reproduction stopped (a target failed) or its main process ended (killed: this
            process would otherwise wait for ever as an orphan) before they were done.
    """
    folder, parent = Path(markers), os.getppid()
    for name in names:
        while not (folder / f"{name}.done").is_file():
            if (folder / "stopped").is_file():
                raise RuntimeError(f"the reproduction stopped before {name} was done (this target reads it)")
            if os.getppid() != parent:  # the reproduction itself was killed: nothing will mark it done
                raise RuntimeError(f"the reproduction ended before {name} was done (this target reads it)")
            time.sleep(poll_s)


class LateNeeds:
    """In a target's process: ``ready(names)`` returns once those of its late needs (all: None) that this
    reproduction runs are done."""

    def __init__(self, markers: str, names: Sequence[str]) -> None:
        self.markers, self.names = markers, tuple(names)

    def __call__(self, names: Sequence[str] | None = None) -> None:
        wait_for(self.markers, [n for n in self.names if names is None or n in names])


def late_needs(markers: str, name: str) -> LateNeeds | None:
    """A target's :class:`LateNeeds` among the targets this reproduction runs (the plan side by side
    wrote), or None when it waits for none."""
    plan = Path(markers) / "plan.json"
    names = json.loads(plan.read_text()).get(name, []) if plan.is_file() else []
    return LateNeeds(markers, names) if names else None


def chain_seconds(order: Sequence[str], needs: dict[str, tuple[str, ...]],
                  late: dict[str, tuple[str, ...]] | None = None) -> dict[str, float]:
    """Per target, its expected seconds plus the longest chain of targets that need it to start (the
    order in which ready targets start: the long chains first, so the last lane does not finish alone).

    A target that ``d`` reads late counts as if ``d`` had ``LATE_SHARE`` of its expected seconds still
    to run when it reads it: so it starts before targets nothing waits for, and ``d`` does not wait.
    """
    late = late or {}
    memo: dict[str, float] = {}

    def chain(target: str) -> float:
        if target not in memo:
            after = [chain(d) for d in order if target in needs.get(d, ())]
            after += [LATE_SHARE * EXPECTED_S.get(d, 0.0) for d in order if target in late.get(d, ())]
            memo[target] = EXPECTED_S.get(target, 0.0) + max(after, default=0.0)
        return memo[target]

    return {t: chain(t) for t in order}


def run_target(name: str, root: str, quick: bool, workers: int, options: dict[str, Any]) -> tuple[str, float]:
    """One target in this (spawned) process, with its own engine answer store: its results folder and wall seconds."""
    from probecommit.report import paper
    from probecommit.tasks.base import shared_engine_answers

    paper.OPTIONS.clear()
    paper.OPTIONS.update(options)
    paper.OPTIONS["_ready"] = late_needs(str(Path(root) / MARKERS), name)  # what it reads last, once done
    _log_target(name)
    start = time.perf_counter()
    with shared_engine_answers():
        folder = paper.TARGETS[name].run(Path(root), quick, paper._noop, workers)
    return str(folder), time.perf_counter() - start


def _log_target(name: str) -> None:
    """Append ``pid target`` to ``$PROBECOMMIT_TARGET_PIDS`` when set: which process runs which target, for a
    memory poller over the whole run (``benchmarks/run_memory.py``; the pool's processes look alike in ``ps``)."""
    log = os.environ.get("PROBECOMMIT_TARGET_PIDS")
    if log:
        with open(log, "a", encoding="utf-8") as out:
            out.write(f"{os.getpid()} {name} {time.time():.1f}\n")


def _start_markers(markers: Path | None, order: Sequence[str], late: dict[str, tuple[str, ...]]) -> None:
    """A fresh markers folder holding the plan: per target, the late needs it waits for."""
    if markers is None:
        return
    shutil.rmtree(markers, ignore_errors=True)
    markers.mkdir(parents=True)
    (markers / "plan.json").write_text(json.dumps({t: list(n) for t, n in late.items() if n}))


def _mark(markers: Path | None, name: str) -> None:
    if markers is not None:
        (markers / name).touch()


def side_by_side(order: Sequence[str], needs: dict[str, tuple[str, ...]], lanes: int,
                 launch: Callable[[ProcessPoolExecutor, str], Future],
                 progress: Callable[[str, int, int], None],
                 rereads: dict[str, tuple[str, ...]] | None = None, markers: Path | None = None,
                 late: dict[str, tuple[str, ...]] | None = None) -> dict[str, tuple[str, float]]:
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
        markers: The folder where finished targets are marked (``<name>.done``) for the targets
            waiting for their late needs (``wait_for``); None: no target waits (``late`` is ignored).
        late: Needs a target reads only in its last steps (default ``LATE_NEEDS``): it starts
            without them and waits for them itself. Needs more than one lane.

    Returns:
        Per target, its results folder and wall seconds (both runs). The first failure is raised
        once the targets already running have finished (their run directories resume).
    """
    rereads = rereads or {}
    late = {t: tuple(n for n in (LATE_NEEDS if late is None else late).get(t, ()) if n in order)
            for t in order} if markers is not None and lanes > 1 else {}
    start_needs = {t: tuple(n for n in needs.get(t, ()) if n not in late.get(t, ())) for t in order}
    first = chain_seconds(order, start_needs, late)
    _start_markers(markers, order, late)
    waiting = list(order)
    running: dict[Future, str] = {}
    done: dict[str, tuple[str, float]] = {}
    stale: set[str] = set()  # finished before what they read: to run again
    failure: BaseException | None = None
    context = multiprocessing.get_context("spawn")  # no fork of a process whose progress bar runs a thread
    with ProcessPoolExecutor(max_workers=lanes, mp_context=context, max_tasks_per_child=1) as pool:
        while waiting or running or stale:
            ready = [t for t in waiting if all(n in done or n not in order for n in start_needs.get(t, ()))]
            ready += [t for t in stale if t not in running.values() and all(r in done for r in rereads[t] if r in order)]
            ready.sort(key=lambda t: -first.get(t, 0.0))
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
                    _mark(markers, "stopped")  # a target waiting for a late need stops too
                    continue
                done[target] = (folder, seconds + (done[target][1] if target in done else 0.0))
                if any(r in order and r not in done for r in rereads.get(target, ())):
                    stale.add(target)
                elif target not in stale:
                    _mark(markers, f"{target}.done")
                progress("targets side by side", len(done), len(order))
    if markers is not None:
        shutil.rmtree(markers, ignore_errors=True)  # every target has finished: nothing waits any more
    if failure is not None:
        raise failure
    return done
