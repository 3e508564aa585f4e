"""A run's final tables, joined and ordered as Arrow tables (``store.canonical``), are byte for byte
the files the DataFrame route wrote: each unit table converted by pandas, joined by ``pd.concat``,
sorted by ``sort_values(kind="stable")``, given the schema's columns and converted back."""

import io

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from probecommit.runner.study import run_study
from probecommit.store import batches
from probecommit.store.rundir import TABLES, _SCHEMAS, arrow_table
from probecommit.store.schema import vector_columns


def _pandas_merge(tables: list[pa.Table]) -> pd.DataFrame:
    """The DataFrame route's join (what ``merge_tables`` did before the Arrow one)."""
    nonempty = [t for t in tables if t.num_rows] or tables[:1]
    if all(t.schema.equals(nonempty[0].schema) for t in nonempty[1:]):
        return pa.concat_tables(nonempty).to_pandas()
    return pd.concat([t.to_pandas() for t in nonempty], ignore_index=True)


def _pandas_canonical(frames: dict[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """The DataFrame route's canonical order and schema columns, written out independently."""
    out = dict(frames)
    instances = frames["instances"].sort_values(["instance_index"], kind="stable", ignore_index=True)
    out["instances"] = instances
    order = {iid: n for n, iid in enumerate(instances["instance_id"].astype(str))}
    for name, keys in (("probes", ["instance_id", "repeat", "j"]), ("episodes", ["instance_id", "repeat"])):
        frame = frames[name]
        pos = frame["instance_id"].astype(str).map(lambda i: order.get(i, len(order))).astype(float)
        out[name] = frame.assign(_pos=pos).sort_values(["_pos", "instance_id", *keys[1:]], kind="stable",
                                                       ignore_index=True).drop(columns="_pos")
    cache = frames["engine_cache"]
    cols = list(cache.columns)
    latents = cols[cols.index("query") + 1: cols.index("arg")]
    args = np.asarray(cache["arg"].tolist(), dtype=float)
    keys = cache[["engine", *latents, "query"]].assign(**{f"_a{i}": args[:, i] for i in range(args.shape[1])})
    out["engine_cache"] = cache.iloc[keys.sort_values(list(keys.columns), kind="stable").index].reset_index(drop=True)
    for name, columns in _SCHEMAS.items():
        frame = out[name]
        names = [n for c in columns for n in (vector_columns(frame.columns, c.name) if c.vector else [c.name]) or [c.name]]
        missing = {n: pd.Series([None] * len(frame), dtype=object) for n in names if n not in frame}
        out[name] = frame.assign(**missing)[names + [c for c in frame.columns if c not in names]]
    return out


def _parquet_bytes(table: pa.Table) -> bytes:
    sink = io.BytesIO()
    pq.write_table(table, sink)
    return sink.getvalue()


@pytest.mark.parametrize("faulty", [False, True], ids=["clean", "failed rollouts and commits"])
def test_final_tables_are_the_bytes_the_dataframe_route_wrote(tmp_path, monkeypatch, make_config, faulty):
    from tests.runner.faults import inject, pick_faults

    cfg = make_config(repeats=3, methods=["blind_bayes", "blind_robust", "probe_robust"], unit_instances=1)
    if faulty:  # the first instance fails in every repeat: the first unit has the rollout rows' columns only
        clean = run_study(cfg, tmp_path / "clean", threads=1).run_dir
        first = pd.read_parquet(clean / "instances.parquet")["true_x_hole"].iloc[0]
        inject(monkeypatch, **{**pick_faults(clean)["faults"], "nan_x": float(first), "nan_u": None})
    run = run_study(cfg, tmp_path / "run", threads=1).run_dir
    units: dict[str, dict[str, pa.Table]] = {}
    for path in sorted((run / "shards").glob("batch-*.pcb")):
        units.update(batches.read(path)[1])
    names = sorted(units)
    frames = _pandas_canonical({t: _pandas_merge([units[u][t] for u in names]) for t in TABLES})
    if faulty:  # the join had to add the columns the first unit lacks, and put them in schema order
        assert set(units[names[0]]["episodes"].column_names) < set(frames["episodes"].columns)
    for name in TABLES:
        expected = _parquet_bytes(arrow_table(frames[name], _SCHEMAS.get(name, ())))
        assert (run / f"{name}.parquet").read_bytes() == expected, name
