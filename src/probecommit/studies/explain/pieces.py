"""A sweep's independent pieces, each a job set aside of its own, merged as the one job would have filled them
(issue 42, target 4).

Why: an engine-setting sweep (ex38's PhysX offsets, ex39's PyBullet plate contacts) is minutes of CPU per point and
its points (or arms) do not read each other. Set aside as one job, its points ran one after another in one of the
pool's two processes, and the explain target's wall was that chain (about 1,200 s each, the target's critical path
with a core idle beside it). As pieces, the pool's processes take them side by side, longest first (the pool is
FIFO: what is submitted first starts first). What a piece needs of another (a bisection needs its grid's ratios)
stays in that piece. The numbers are the same: each piece is the function the one job called, on the same
arguments, and :attr:`Pieces.combine` puts the results together in the order the one job concatenated them.

A sweep module offers ``pieces(job) -> Pieces | None`` (None: nothing to run, as its step returning early) and
keeps ``run(job) = in_place(job, pieces)``; the explain target sets it aside with ``Explain.split(module.pieces)``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

#: What ``combine`` returns: ``{"res": {group: keys}, "stored": {file: rows}}``, as a job set aside fills them.
Filled = dict[str, dict[str, Any]]


@dataclass(frozen=True)
class Pieces:
    """A sweep cut into independent pieces.

    ``calls``: each piece's module-level function and its picklable arguments, in the order the one job ran them;
    ``costs``: a guess of each piece's CPU, only to submit the longest first (ties in ``calls`` order);
    ``combine(results)``: the results in ``calls`` order put together (``Filled``), in the process that merges."""

    calls: Sequence[tuple[Callable[..., Any], tuple]]
    costs: Sequence[float]
    combine: Callable[[list[Any]], Filled]

    def __post_init__(self) -> None:
        if len(self.calls) != len(self.costs):
            raise ValueError(f"{len(self.calls)} pieces, {len(self.costs)} costs")
        if not self.calls:  # nothing would hand the combined keys on
            raise ValueError("a sweep of no pieces: its pieces(job) returns None instead")

    def order(self) -> list[int]:
        """The pieces' submission order: longest guessed cost first, ties in ``calls`` order."""
        return sorted(range(len(self.calls)), key=lambda i: -float(self.costs[i]))


def timed(fn: Callable[..., Any], *args: Any) -> tuple[Any, tuple[str, float, float, float], float]:
    """``fn(*args)`` in a process set aside, with engine answers shared as in a job aside (``run_aside``): its result,
    its clock (``(label, wall_s, cpu_s, child_cpu_s)``, as ``StepClock.steps``) and the process's peak MB."""
    from probecommit.studies.explain.timing import children_cpu, peak_mb
    from probecommit.tasks.base import shared_engine_answers

    wall, cpu, children = time.perf_counter(), time.process_time(), children_cpu()
    with shared_engine_answers():
        result = fn(*args)
    label = f"{fn.__module__.rsplit('.', 1)[-1]}.{fn.__name__}{_short(args)}"
    return result, (label, time.perf_counter() - wall, time.process_time() - cpu, children_cpu() - children), peak_mb()


def _short(args: tuple) -> str:
    """The plain arguments of a piece (its arm, value or index), for its clock's label."""
    plain = [repr(a) for a in args if isinstance(a, (str, int, float)) and not isinstance(a, bool)]
    return f"({', '.join(plain)})" if plain else ""


def gather(pieces: Pieces, results: dict[int, Any]) -> dict[str, Any]:
    """Every piece's ``timed`` result (by piece number) put together: what ``run_aside`` hands back for one job."""
    ordered = [results[i] for i in range(len(pieces.calls))]
    filled = pieces.combine([result for result, _, _ in ordered])
    return {"res": filled.get("res", {}), "stored": filled.get("stored", {}), "tables": {},
            "steps": [clock for _, clock, _ in ordered], "peak_mb": max((peak for _, _, peak in ordered), default=0.0)}


def in_place(job: Any, plan: Callable[[Any], Pieces | None]) -> None:
    """The sweep as one step (``run(job)``): every piece here in ``calls`` order, the results combined into
    ``job.res`` and ``job.stored``."""
    pieces = plan(job)
    if pieces is None:
        return
    filled = pieces.combine([fn(*args) for fn, args in pieces.calls])
    for group, keys in filled.get("res", {}).items():
        job.res[group].update(keys)
    job.stored.update(filled.get("stored", {}))
