"""A replay's engine answers kept as columns (``CachedSimulator.answer_columns``) make the table the
records made (``cache_records``), bit for bit and schema alike (issue 42: calibrate's per-chunk answers)."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.runner.replay import StoredAnswers
from probecommit.store.schema import cache_frame
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator

LATENTS = ("x_hole", "c")


def _kept(records) -> pa.Table:
    stored = [{"engine": "analytic", "query": "peg_depth", "theta": [9.0, 1.0], "arg": [9.0], "value": [15.0]}]
    answers = StoredAnswers(pa.Table.from_pandas(cache_frame(stored, LATENTS), preserve_index=False), LATENTS)
    answers.add(records)
    answers.merge_added()
    return answers.table()


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["tap_reading", "peg_depth"]), st.sampled_from([-0.0, 0.0, 1.5, -2.25]),
                          st.sampled_from([0.0, 2.0]), st.sampled_from([-0.0, 0.5, 3.0, 7.0])), min_size=1, max_size=8))
def test_answers_kept_as_columns_are_the_records_table(queries):
    sim = AnalyticInsertionSimulator()
    for kind, x, c, q in queries:
        sim.query(kind, x, c, q)
    keys = sim.answered_keys()
    by_columns, by_records = _kept(sim.answer_columns(keys)), _kept(sim.cache_records(keys))
    assert by_columns.equals(by_records, check_metadata=True)
    assert [np.signbit(v) for v in by_columns.column("x_hole").to_pylist()] == \
        [np.signbit(v) for v in by_records.column("x_hole").to_pylist()]


def test_answers_of_different_lengths_are_left_to_the_records():
    sim = AnalyticInsertionSimulator()
    sim._cache[("peg_depth", (1.0, 2.0), (3.0,))] = np.array([1.0])
    sim._cache[("peg_depth", (1.0, 2.0), (3.0, 4.0))] = np.array([1.0])
    assert sim.answer_columns(sim.answered_keys()) is None and sim.answer_columns([]) is None
