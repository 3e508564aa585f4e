"""The per-budget summary in NumPy (report/tables.py) equals pandas' grouped means, from a DataFrame and
from the Arrow table a run prints: counts, order and means (within 1e-12: NumPy sums pairwise, pandas
with compensation)."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.report.tables import METHOD_ORDER, SUMMARY_COLUMNS, budget_rows, budget_summary, summary_columns

NUMBERS = ("failure", "predicted", "optimism", "coverage", "escape")
METHODS = ["blind_bayes", "blind_robust", "probe_robust", "rollout", "alpha", "zeta", None]


def pandas_reference(episodes: pd.DataFrame) -> list[dict]:
    """The summary as a pandas groupby gives it (the function ``budget_summary`` was before NumPy)."""
    ok = episodes[episodes["status"] == "ok"]
    grouped = ok.groupby(["method", "k"], sort=True)
    table = pd.DataFrame({"episodes": grouped.size(), "failure": grouped["realized"].mean(),
                          "predicted": grouped["predicted"].mean(), "coverage": grouped["covered"].mean(),
                          "escape": grouped["escaped"].mean()})
    table["optimism"] = table["failure"] - table["predicted"]
    failed = episodes[episodes["status"] != "ok"].groupby(["method", "k"]).size()
    table["failed"] = failed.reindex(table.index).fillna(0).astype(int)
    table = table.reset_index()
    table["rank"] = table["method"].map(METHOD_ORDER).fillna(len(METHOD_ORDER))
    table = table.sort_values(["rank", "method", "k"]).drop(columns="rank")  # other methods by name, each by k
    return table.to_dict("records")


def assert_same_rows(got: list[dict], want: list[dict]) -> None:
    assert [(r["method"], r["k"], r["episodes"], r["failed"]) for r in got] == \
        [(r["method"], r["k"], r["episodes"], r["failed"]) for r in want]
    for a, b in zip(got, want):
        for name in NUMBERS:
            x, y = float(a[name]), float(b[name])
            assert (math.isnan(x) and math.isnan(y)) or x == pytest.approx(y, rel=1e-12, abs=1e-12), (name, a, b)


@st.composite
def episode_frames(draw) -> pd.DataFrame:
    """Episodes of random methods (unknown names and a missing one too), budgets, statuses (missing too)
    and outcomes: 0/1 or continuous, with NaN."""
    n = draw(st.integers(0, 40))
    binary = draw(st.booleans())
    outcome = st.sampled_from([0.0, 1.0]) if binary else st.floats(-10, 10, allow_nan=False)
    value = st.one_of(outcome, st.just(float("nan"))) if draw(st.booleans()) else outcome
    rows = [{"method": draw(st.sampled_from(METHODS)), "k": draw(st.integers(0, 3)),
             "status": draw(st.sampled_from(["ok", "ok", "failed", None])), "realized": draw(value),
             "predicted": draw(value), "covered": draw(value), "escaped": draw(value)} for _ in range(n)]
    return pd.DataFrame(rows, columns=["method", "k", "status", "realized", "predicted", "covered", "escaped"])


@settings(max_examples=200, deadline=None)
@given(episode_frames())
def test_the_numpy_rows_equal_pandas_groupby(frame):
    want = pandas_reference(frame)
    assert_same_rows(budget_rows(summary_columns(frame)), want)
    assert_same_rows(budget_rows(summary_columns(pa.Table.from_pandas(frame, preserve_index=False))), want)
    assert_same_rows(budget_summary(frame).to_dict("records"), want)


def test_a_hand_case_with_exact_answers():
    """Failed and missing-status rows counted, a NaN skipped, a failed-only group and a missing method
    dropped, other methods after the known ones by name (then k), a boolean column with a null."""
    frame = pd.DataFrame({
        "method": ["probe_robust", "probe_robust", "probe_robust", "probe_robust", "blind_bayes", "zeta", "alpha",
                   "alpha", "rollout", None],
        "k": [1, 1, 1, 1, 0, 0, 1, 0, 0, 0],
        "status": ["ok", "ok", "ok", "failed", "ok", "ok", "ok", None, "failed", "ok"],
        "realized": [1.0, 0.0, np.nan, np.nan, 1.0, 0.0, 1.0, 1.0, np.nan, 1.0],
        "predicted": [0.25, 0.5, 0.75, 0.5, 0.5, 0.0, 0.5, 0.5, np.nan, 0.0],
        "covered": [True, False, True, None, True, False, True, True, None, True],
        "escaped": [False, False, True, False, False, True, False, False, False, False],
    })
    rows = budget_rows(summary_columns(pa.Table.from_pandas(frame, preserve_index=False)))
    assert rows == [
        {"method": "blind_bayes", "k": 0, "episodes": 1, "failure": 1.0, "predicted": 0.5, "optimism": 0.5,
         "coverage": 1.0, "escape": 0.0, "failed": 0},
        {"method": "probe_robust", "k": 1, "episodes": 3, "failure": 0.5, "predicted": 0.5, "optimism": 0.0,
         "coverage": 2 / 3, "escape": 1 / 3, "failed": 1},
        {"method": "alpha", "k": 1, "episodes": 1, "failure": 1.0, "predicted": 0.5, "optimism": 0.5,
         "coverage": 1.0, "escape": 0.0, "failed": 0},
        {"method": "zeta", "k": 0, "episodes": 1, "failure": 0.0, "predicted": 0.0, "optimism": 0.0,
         "coverage": 0.0, "escape": 1.0, "failed": 0},
    ]
    assert budget_rows(summary_columns(frame)) == rows
    assert_same_rows(rows, pandas_reference(frame))


def test_the_frame_keeps_the_columns_types_also_empty():
    frame = pd.DataFrame({"method": ["probe_robust"], "k": [2], "status": ["failed"], "realized": [1.0],
                          "predicted": [0.5], "covered": [True], "escaped": [False]})
    table = budget_summary(frame)
    assert table.empty and list(table.columns) == list(SUMMARY_COLUMNS)
    assert {c: str(t) for c, t in table.dtypes.items()} == {
        "method": str(frame["method"].dtype), "k": "int64", "episodes": "int64", "failure": "float64",
        "predicted": "float64", "optimism": "float64", "coverage": "float64", "escape": "float64", "failed": "int64"}


READ = """
import sys
import pyarrow.parquet as pq
from probecommit.report.tables import budget_rows, summary_columns
rows = budget_rows(summary_columns(pq.ParquetFile(sys.argv[1]).read()))
print(len(rows), rows[0]["failed"], "pandas" in sys.modules)
"""


def test_a_table_with_failed_rows_nulls_and_other_methods_is_summed_without_pandas(tmp_path):
    """A run's table with failed rows (a rollout's row has no ``covered``: a boolean column with a null)
    is summarized without importing pandas too, as a clean run's is."""
    frame = pd.DataFrame({"method": ["probe_robust", "probe_robust", "rollout", "alpha"], "k": [1, 1, 0, 1],
                          "status": ["ok", "failed", "failed", "ok"], "realized": [1.0, np.nan, np.nan, 0.0],
                          "predicted": [0.5, 0.5, np.nan, 0.0], "covered": [True, False, None, True],
                          "escaped": [False, False, None, False]})
    frame.to_parquet(tmp_path / "episodes.parquet", index=False)
    done = subprocess.run([sys.executable, "-c", READ, str(tmp_path / "episodes.parquet")], capture_output=True,
                          text=True, check=True)
    assert done.stdout.split() == ["2", "1", "False"], done.stdout + done.stderr
