"""The final tables built in Arrow alone (``rundir.arrow_canonical_tables``) are the pandas path's,
byte for byte, or the Arrow path declines and the pandas path writes them."""

import io

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.store import rundir
from probecommit.store.rundir import (_SCHEMAS, arrow_canonical_tables, arrow_from_columns, arrow_table,
                                      canonical_tables, merge_tables)
from probecommit.store.schema import EPISODE_COLUMNS, INSTANCE_COLUMNS, PROBE_COLUMNS


def _parquet(table: pa.Table) -> bytes:
    sink = io.BytesIO()
    pq.write_table(table, sink)
    return sink.getvalue()


def _pandas_final(tables: dict[str, list[pa.Table]]) -> dict[str, bytes]:
    """What ``finalize`` wrote before the Arrow path: merged and ordered through pandas."""
    frames = {name: merge_tables(parts) for name, parts in tables.items()}
    return {name: _parquet(arrow_table(frame, _SCHEMAS[name])) for name, frame in canonical_tables(frames).items()}


def _unit(ids, indexes, rows, nan_at, seed):
    """One unit's instances, probes and episodes tables as a unit builds them (``arrow_from_columns``)."""
    rng = np.random.default_rng(seed)
    n = len(rows)
    rid = np.array([r[0] for r in rows], dtype=object).astype(str)
    rep = np.array([r[1] for r in rows], dtype=np.int64)
    value = rng.normal(size=n)
    value[[i for i in nan_at if i < n]] = np.nan  # NaN in a float column: null, as from pandas
    instances = arrow_from_columns({"instance_id": np.array(ids, dtype=str), "split": "s",
                                    "instance_index": np.array(indexes, dtype=np.int64),
                                    "true_x": rng.normal(size=len(ids))}, len(ids), INSTANCE_COLUMNS)
    probes = arrow_from_columns({"instance_id": rid, "repeat": rep, "j": np.array([r[2] for r in rows], dtype=np.int64),
                                 "u": value, "y": -value}, n, PROBE_COLUMNS)
    filled = {str(pa.float64()): value, str(pa.bool_()): value > 0, str(pa.int64()): np.arange(n, dtype=np.int64),
              str(pa.string()): "ok"}
    episodes = arrow_from_columns({**{c.name: filled[str(c.type)] for c in EPISODE_COLUMNS},  # every column, in order
                                   "instance_id": rid, "repeat": rep, "k": np.array([r[2] for r in rows], dtype=np.int64),
                                   "error": np.where(np.isnan(value), "nan", "")}, n, EPISODE_COLUMNS)
    return {"instances": instances, "probes": probes, "episodes": episodes}


@st.composite
def _units(draw):
    """Units of instances (indexes shuffled across units), their rows in any order, some rows of
    ids no instance has, some float values missing."""
    n = draw(st.integers(1, 8))
    indexes = draw(st.permutations(list(range(n))))
    ids = [f"s-{9990 + i}" for i in indexes]  # s-9999 before s-10000: the instance order, not the text's
    cuts = sorted(draw(st.lists(st.integers(0, n), max_size=3)))
    bounds = [0, *cuts, n]
    units = []
    for u, (a, b) in enumerate(zip(bounds, bounds[1:])):
        if a == b:
            continue
        pool = ids[a:b] + (["zz-stray"] if draw(st.booleans()) else [])
        rows = draw(st.lists(st.tuples(st.sampled_from(pool), st.integers(0, 2), st.integers(0, 3)), min_size=1,
                             max_size=12))
        nan_at = draw(st.lists(st.integers(0, 11), max_size=3))
        units.append(_unit(ids[a:b], indexes[a:b], rows, nan_at, u))
    return units


@settings(max_examples=40, deadline=None)
@given(_units())
def test_the_arrow_tables_are_the_pandas_paths_byte_for_byte(units):
    tables = {name: [unit[name] for unit in units] for name in _SCHEMAS}
    built = arrow_canonical_tables(tables)
    assert built is not None  # plain columns, nulls only in floats: the Arrow path answers
    expected = _pandas_final(tables)
    for name in _SCHEMAS:
        assert _parquet(built[name]) == expected[name], name


def _three_units():
    return [_unit([f"s-{i}"], [i], [(f"s-{i}", r, j) for r in range(2) for j in range(3)], [1], i) for i in range(3)]


def _tables(units):
    return {name: [unit[name] for unit in units] for name in _SCHEMAS}


def test_the_arrow_path_declines_where_pandas_could_give_another_table():
    units = _three_units()
    assert arrow_canonical_tables(_tables(units)) is not None
    # A unit whose episodes lack columns (failed rollouts only): the schemas differ.
    odd = [dict(u) for u in units]
    odd[1]["episodes"] = odd[1]["episodes"].drop_columns(["action", "predicted"])
    assert arrow_canonical_tables(_tables(odd)) is None
    # Every unit without a schema column (pandas adds it, empty).
    odd = [{**u, "episodes": u["episodes"].drop_columns(["z_true"])} for u in units]
    assert arrow_canonical_tables(_tables(odd)) is None
    # A null in an int column (pandas makes it a float) and a NaN kept as a value (pandas makes it null).
    for column, value in (("n_retained", pa.array([None] * 6, pa.int64())),
                          ("action", pa.array([float("nan")] * 6, pa.float64()))):
        bad = [dict(u) for u in units]
        episodes = bad[2]["episodes"]
        bad[2]["episodes"] = episodes.set_column(episodes.schema.get_field_index(column), column, value)
        assert bad[2]["episodes"].schema.equals(episodes.schema)
        assert arrow_canonical_tables(_tables(bad)) is None, column


@pytest.mark.parametrize("family", ["insertion", "planar_slide"], ids=["insertion", "vector actions"])
def test_a_runs_files_are_those_the_pandas_path_writes(tmp_path, monkeypatch, family):
    """A run's final files, with the Arrow path and with it declined: identical bytes; and the Arrow
    path wrote them."""
    from probecommit.runner.config import parse_config
    from probecommit.runner.study import run_study

    contexts = {"contexts": [[1.0, 0.2], [0.6, -0.3]]} if family == "planar_slide" else {}
    config = parse_config({"name": "af", "task": family, "seed": 5, "repeats": 2, "probes": {"budget": 3},
                           "instances": {"split": "t", "count": 6, "seed": 1, **contexts}, "belief": {"particles": 64},
                           "simulator": {"engine": "analytic"}, "blind_prior_samples": 200, "unit_instances": 2})
    answered = []
    real = rundir.arrow_canonical_tables
    monkeypatch.setattr(rundir, "arrow_canonical_tables", lambda tables: answered.append(real(tables)) or answered[-1])
    run_study(config, tmp_path / "arrow", threads=1)
    assert answered and answered[-1] is not None
    monkeypatch.setattr(rundir, "arrow_canonical_tables", lambda tables: None)
    run_study(config, tmp_path / "pandas", threads=1)
    for name in rundir.TABLES:
        path = f"{name}.parquet"
        assert (tmp_path / "arrow" / path).read_bytes() == (tmp_path / "pandas" / path).read_bytes(), name
