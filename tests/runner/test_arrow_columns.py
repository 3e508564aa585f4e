"""Arrow columns built from buffers (store/arrow_columns.py) equal pyarrow's own conversions, and a
run's process never imports pandas (issue 42, target 2)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.store.arrow_columns import column_array, indices, pandas_metadata, strings, to_numpy
from probecommit.store.rundir import _inferred_array

N = 4
COLUMNS = {
    "floats": np.array([0.5, np.nan, -np.inf, 2.0]),
    "float32": np.array([0.5, np.nan, 1.0, 2.0], dtype=np.float32),
    "ints": np.arange(N, dtype=np.int64),
    "int32": np.arange(N, dtype=np.int32),
    "bools": np.array([True, False, True, True]),
    "unicode": np.array(["a", "bé", "", "c"]),
    "objects": np.array(["a", None, "x", "y"], dtype=object),
    "object_first_none": np.array([None, "a", "b", "c"], dtype=object),
    "nones": np.array([None] * N, dtype=object),
    "float_list": [0.5, None, float("nan"), 1.0],
    "int_list": [1, 2, 3, 4],
    "bool_list": [True, False, False, True],
    "str_list": ["tap", "aim", "tap", "tap"],
    "vectors": [[0.0], [1.0, 2.0], [], [3.0]],
    "numpy_vectors": [list(np.array([0.5, 1.5])), [1.0, 2.0], [0.0, 0.0], [2.0, 3.0]],
    "int_scalar": np.int64(3),
    "str_scalar": "rollout",
    "float_scalar": 0.25,
}


@pytest.mark.parametrize("name", sorted(COLUMNS))
def test_a_column_built_from_buffers_equals_pyarrows_conversion(name):
    value = COLUMNS[name]
    built, expected = column_array(value, N), _inferred_array(value, N)  # what arrow_from_columns built before
    assert built is not None
    assert built.type == expected.type and built.null_count == expected.null_count
    assert built.equals(expected), (built, expected)


@pytest.mark.parametrize("name", sorted(COLUMNS))
def test_hand_written_pandas_metadata_equals_pandas_own(name):
    """The metadata of a one-row DataFrame of the column's first value, byte for byte."""
    value = COLUMNS[name]
    columns = {name: value}
    sample = pd.DataFrame({name: (value[:1] if isinstance(value, (list, np.ndarray)) else value)}, index=range(1))
    expected = pa.Schema.from_pandas(sample, preserve_index=False).metadata
    assert pandas_metadata(columns, [column_array(value, N)]) == expected


def test_columns_of_mixed_kinds_are_left_to_pyarrow():
    """None, so ``arrow_from_columns`` takes pyarrow's inference (and pandas' metadata)."""
    assert column_array(["a", 1.0, None, "b"], N) is None
    assert column_array(np.array([1.0, "a", 2.0, 3.0], dtype=object), N) is None
    assert column_array([[0.0], [float("nan")], [1.0], [2.0]], N) is None  # NaN inside a list
    mixed = np.array([1.5, 2.5, 3.5, 4.5], dtype=object)  # pandas keeps an object array's dtype
    assert pandas_metadata({"x": mixed}, [pa.array(mixed.tolist())]) is None


ARRAYS = {
    "ints": pa.array([3, 1, 2, 5], type=pa.int64()),
    "int_nulls": pa.array([3, None, 2, 5], type=pa.int64()),
    "int32_nulls": pa.array([None, 1, 2, None], type=pa.int32()),
    "floats": pa.array([0.5, None, 2.0, -1.0]),
    "bools": pa.array([True, False, False, True]),
    "sliced": pa.array([9.0, 0.5, 1.5, 2.5, 3.5, None, 7.0]).slice(1, 4),
    "sliced_nulls": pa.array([9.0, None, 1.5, None, 3.5, 4.0, None, 7.0, None, 1.0]).slice(1, 8),
    "sliced_int_nulls": pa.array([1, None, 3, None, 5, 6, None, 8, 9, None], type=pa.int64()).slice(3, 6),
    "sliced_bools": pa.array([True, False, True, True, False, False, True, True, False]).slice(3, 5),
    "chunked": pa.chunked_array([[1, 2], [3, None]], type=pa.int64()),
}


@pytest.mark.parametrize("name", sorted(ARRAYS))
def test_a_column_read_from_its_buffers_equals_to_numpy(name):
    column = ARRAYS[name]
    expected = column.to_numpy(zero_copy_only=False) if isinstance(column, pa.Array) else column.to_numpy()
    got = to_numpy(column)
    assert got.dtype == expected.dtype
    np.testing.assert_array_equal(got, expected)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.one_of(st.none(), st.text(max_size=5)), min_size=1, max_size=12), st.data())
def test_strings_and_take_positions_equal_pyarrows(values, data):
    assert strings(values).equals(pa.array(values, type=pa.large_string()))
    order = data.draw(st.permutations(range(len(values))))
    table = pa.table({"s": pa.array(values, type=pa.large_string())})
    assert table.take(indices(np.array(order, dtype=np.int64))).equals(table.take(order))


RUN = textwrap.dedent("""
    import sys
    from typer.testing import CliRunner
    from probecommit.cli.app import app
    result = CliRunner().invoke(app, ["run", sys.argv[1], "--out", sys.argv[2], "--threads", "1"])
    assert result.exit_code == 0, result.output
    print("Probe-Robust" in result.output, "pandas" in sys.modules)
""")


def test_a_run_as_the_command_runs_it_never_imports_pandas(tmp_path):
    """pandas' import was about 0.2 s of a run's CPU (docs/decisions.md, "run: ..."): the command's
    own path (config, units, batches, merge, final tables, summary) needs none."""
    config = tmp_path / "c.yaml"
    config.write_text("name: nopandas\nseed: 1\nrepeats: 2\ninstances: {split: t, count: 6, seed: 1}\n"
                      "probes: {schedule: random, budget: 3}\nbelief: {particles: 64}\nsimulator: {engine: analytic}\n"
                      "unit_instances: 2\n")
    done = subprocess.run([sys.executable, "-c", RUN, str(config), str(tmp_path / "run")], capture_output=True,
                          text=True, check=True)
    assert done.stdout.split() == ["True", "False"], done.stdout + done.stderr


def test_the_commands_summary_rows_equal_budget_summary(tmp_path):
    from probecommit.report.tables import budget_rows, budget_summary, summary_columns
    from probecommit.runner.config import parse_config
    from probecommit.runner.study import run_study

    config = parse_config({"name": "rows", "seed": 5, "repeats": 2, "instances": {"split": "t", "count": 6, "seed": 2},
                           "probes": {"budget": 3}, "belief": {"particles": 64}, "simulator": {"engine": "analytic"},
                           "methods": ["blind_bayes", "probe_robust"], "blind_prior_samples": 200})
    result = run_study(config, tmp_path / "run")
    rows = budget_rows(summary_columns(result.episodes_table))
    expected = budget_summary(result.episodes).to_dict("records")
    assert [(r["method"], r["k"], r["episodes"], r["failed"]) for r in rows] == \
        [(r["method"], r["k"], r["episodes"], r["failed"]) for r in expected]
    for got, want in zip(rows, expected):
        for name in ("failure", "predicted", "optimism", "coverage", "escape"):
            assert got[name] == pytest.approx(want[name], rel=1e-12, abs=1e-15)
    assert json.dumps(rows)  # plain Python values


@pytest.mark.parametrize("resets", [[0, 2, None, 1], [None, None, None, None]], ids=["counts", "all null"])
def test_a_results_reset_and_failed_rows_are_counted_as_the_dataframe_counts_them(resets):
    from probecommit.runner.study import StudyResult

    table = pa.table({"status": pa.array(["ok", "failed", None, "ok"]),
                      "belief_resets": pa.array(resets, type=pa.int64() if resets[0] is not None else pa.null())})
    result = StudyResult(None, {}, table)
    frame = result.episodes
    assert result.failed_episodes == int((frame["status"] != "ok").sum())
    assert result.belief_reset_rows == int((frame["belief_resets"].fillna(0) > 0).sum())
