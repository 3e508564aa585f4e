"""A run's beliefs computed once and handed to every calibration, gate and audit that reads them.

Several explain steps re-commit the same stored run under other thresholds: each fresh draw of
the generator is audited under the frozen calibration, tested under a calibration on the next
draw, and calibrates the previous one, for Table III's cells and for the random-probe gates (five
belief recomputations of one run, issue 42). An episode's beliefs never depend on the batch or
the budgets they are computed with (``tests/runner/test_batch_independence.py``), so one trace of
the whole run, every budget kept, gives each of those commits the beliefs it would have computed
itself: the tables, hence every number, are the same bits.

:func:`with_beliefs` hands out a :class:`~probecommit.runner.replay.LoadedRun` carrying its own
:class:`~probecommit.runner.replay.RunBeliefs` over the shared trace (restricted to the budgets the
caller asks for), so a calibration's ``release`` drops only its own view, never the shared trace.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable, Iterable, Sequence, TypeVar

from probecommit.runner.inference import BeliefTrace
from probecommit.runner.replay import LoadedRun, RunBeliefs, load_run

T = TypeVar("T")
U = TypeVar("U")


class SharedBeliefs:
    """Per run directory, its loaded run and its whole-run belief trace, kept until :meth:`drop`.

    ``budgets``: the only budgets any caller reads (None: every budget and the prior). A trace of five of a
    run's eight budgets and no prior holds about half the arrays (issue 42, target 4: two runs are held at
    once); an episode's belief at a budget does not depend on which budgets are kept, so the numbers are the same.
    """

    def __init__(self, budgets: Iterable[int] | None = None) -> None:
        self._held: dict[Path, tuple[LoadedRun, RunBeliefs, BeliefTrace]] = {}
        self._budgets = None if budgets is None else sorted(dict.fromkeys(int(k) for k in budgets))

    def _whole(self, path: Path) -> tuple[LoadedRun, RunBeliefs, BeliefTrace]:
        path = Path(path)
        if path not in self._held:
            loaded = load_run(path)
            beliefs = RunBeliefs.of(loaded, chunk_instances=None, budgets=self._budgets)  # one chunk
            self._held[path] = loaded, beliefs, beliefs.trace(beliefs.chunks[0])
        return self._held[path]

    def run(self, path: str | Path, budgets: Iterable[int] | None = None) -> LoadedRun:
        """The run at ``path`` with beliefs at ``budgets`` (None: all, the prior too) from the shared trace:
        what ``load_for_commit(path, budgets=budgets)`` would compute, without computing it."""
        if budgets is None and self._budgets is not None:
            raise ValueError(f"every budget and the prior asked of beliefs kept at {self._budgets} only")
        loaded, whole, trace = self._whole(Path(path))
        if budgets is None:
            view = replace(whole, _kept=(trace, {}))
        else:
            kept = tuple(sorted(dict.fromkeys(int(k) for k in budgets)))
            missing = [k for k in kept if k not in trace.states]
            if missing:
                raise ValueError(f"budget(s) {missing} not in the run {path} (it commits at {trace.budgets})")
            part = BeliefTrace(trace.batch, {k: trace.states[k] for k in kept}, trace.surprise, trace.lost)
            view = replace(whole, kept_budgets=kept, _kept=(part, {}))
        return LoadedRun(loaded.path, loaded.config, loaded.instances, manifest=loaded.manifest, beliefs=view)

    def drop(self, path: str | Path) -> None:
        """Forget a run's trace (no later step reads it)."""
        self._held.pop(Path(path), None)

    def __contains__(self, path: object) -> bool:
        return Path(path) in self._held  # type: ignore[arg-type]


def cyclic_pairs(paths: Sequence[Path], pair: Callable[[Path, Path], T], shared: SharedBeliefs,
                 first: Callable[[Path], U] | None = None) -> tuple[list[U], list[T]]:
    """``pair(cal, test)`` for each run ``i`` tested under a calibration on run ``i + 1`` (cyclic: the last on
    the first), and ``first(run)`` of each run, where both read the runs' beliefs from ``shared``
    (``shared.run(path, budgets)``): every run's beliefs are computed once (the first run's twice).

    The pairs are evaluated as their runs arrive (``i`` once ``i + 1`` is there), so at most two runs'
    beliefs are held at once; each result is a function of its pair alone, so the order changes no number.

    Returns:
        ``first``'s results (empty without it) and ``pair``'s, both in the order of ``paths``.
    """
    n = len(paths)
    firsts: list[U] = []
    out: list[T | None] = [None] * n
    for j, path in enumerate(paths):
        if first is not None:
            firsts.append(first(path))
        if j >= 1:
            out[j - 1] = pair(path, paths[j - 1])
            shared.drop(paths[j - 1])
    if n > 1:
        out[n - 1] = pair(paths[0], paths[n - 1])
    for path in paths:
        shared.drop(path)
    return firsts, out  # type: ignore[return-value]
