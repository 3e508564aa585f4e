"""The insertion simulators' commits of many (instance, aim) pairs at once equal one ``execute`` each (issue 42)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.tasks.base import CachedSimulator
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator


class Broken(AnalyticInsertionSimulator):
    """An engine whose peg depth is NaN left of x = 0 and raises at aim 7.0 (errors to be reported)."""

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        if a == 7.0:
            raise RuntimeError("the peg jammed")
        return float("nan") if x_hole < 0 else super().peg_depth(x_hole, c, a)


def _one_by_one(sim, thetas, actions) -> list:
    return CachedSimulator.realized_many(sim, thetas, actions)


def _same(a: list, b: list) -> bool:
    return [repr(x) if isinstance(x, Exception) else x for x in a] == [repr(x) if isinstance(x, Exception) else x for x in b]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([-1.5, 0.0, -0.0, 2.5]), st.sampled_from([0.0, 1.0, 3.0]),
                          st.sampled_from([-3.0, -0.0, 0.0, 1.25, 2.5, 4.0, 7.0])), max_size=10),
       st.sampled_from([0.0, 0.5, -7.0]), st.booleans())
def test_realized_many_is_execute_row_by_row(rows, offset, stored):
    """Values, errors (NaN depth, an engine that raises), engine calls and the cache are the same as
    ``execute`` row by row, whether the answers are stored already or asked of the engine."""
    thetas = np.array([[x, c] for x, c, _ in rows], dtype=float).reshape(len(rows), 2)
    actions = np.array([[a] for *_, a in rows], dtype=float).reshape(len(rows), 1)
    fast, slow = Broken(aim_offset=offset), Broken(aim_offset=offset)
    if stored:  # half the answers given before, as a replay's stored cache
        for sim in (fast, slow):
            _one_by_one(sim, thetas[::2], actions[::2])
    assert _same(fast.realized_many(thetas, actions), _one_by_one(slow, thetas, actions))
    assert fast.engine_calls == slow.engine_calls
    assert list(fast._cache) == list(slow._cache)


def test_a_subclass_with_its_own_execute_is_executed_row_by_row():
    class Inverted(AnalyticInsertionSimulator):
        def execute(self, theta, action, context=None):
            return {"realized": 1.0 - super().execute(theta, action, context)["realized"]}

    thetas, actions = np.array([[0.0, 1.0], [0.0, 1.0]]), np.array([[0.0], [9.0]])
    assert Inverted().realized_many(thetas, actions) == [1.0, 0.0]
    assert AnalyticInsertionSimulator().realized_many(thetas, actions) == [0.0, 1.0]
