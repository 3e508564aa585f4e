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


_VALUES = st.sampled_from([-0.0, 0.0, 1.5, -2.25, 3.0, float("nan")])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(_VALUES, _VALUES), min_size=1, max_size=12),
       st.lists(st.tuples(_VALUES, _VALUES), min_size=1, max_size=4))
def test_about_selects_the_rows_whose_every_latent_is_among_the_truths(thetas, truths):
    """``about`` looks a column's distinct values up: the same rows as ``np.isin`` on every row (signed
    zeros, NaN), for the run's table and for a table of answers added after it."""
    stored = [{"engine": "analytic", "query": "peg_depth", "theta": [x, c], "arg": [float(i)], "value": [1.0]}
              for i, (x, c) in enumerate(thetas)]
    table = pa.Table.from_pandas(cache_frame(stored, LATENTS), preserve_index=False)
    answers = StoredAnswers(table, LATENTS)
    answers.add(stored)
    truths = np.array(truths, dtype=float)
    expected = np.ones(len(thetas), dtype=bool)
    for j, name in enumerate(LATENTS):
        expected &= np.isin(np.asarray(table.column(name).to_numpy(), dtype=float), truths[:, j])
    masks = answers.about(truths)
    assert len(masks) == 2 and all(mask.dtype == bool and np.array_equal(mask, expected) for mask in masks)
