"""The final tables of a run, as Arrow tables: the units' tables joined and put in canonical order.

Built on Arrow and NumPy, so writing a run's final tables does not convert every table to a
DataFrame and back (and sort it there). What comes out is what the same steps gave on
DataFrames (``pd.concat``, ``sort_values(kind="stable")``, the schema's columns added and
ordered, ``Table.from_pandas``): the same rows, order and types, byte for byte once written
(``tests/runner/test_canonical.py``). Tables only pandas can join as it did (units of
different columns, empty tables, whose column types pandas decides) are joined by pandas.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from probecommit.store.arrow_columns import indices, strings, to_numpy
from probecommit.store.schema import Column, float_matrix, vector_columns


def merge_arrow(tables: list[pa.Table]) -> pa.Table | None:
    """One table of several units' tables, in their order: their rows (the empty ones only when
    every table is empty), as ``pd.concat`` of each converted alone gives them (None: no tables).

    Tables of one schema and metadata (the usual case) are joined as Arrow tables; otherwise
    (a unit whose every trajectory failed has only the rollout rows' columns, or the tables are
    empty) pandas joins them, as it always did, and the joined frame is converted once.
    """
    if not tables:
        return None
    nonempty = [t for t in tables if t.num_rows] or tables[:1]
    if nonempty[0].num_rows and all(t.schema.equals(nonempty[0].schema, check_metadata=True) for t in nonempty[1:]):
        return pa.concat_tables(nonempty)
    import pandas as pd

    frame = pd.concat([t.to_pandas() for t in nonempty], ignore_index=True)
    return pa.Table.from_pandas(frame, preserve_index=False, nthreads=1)


def canonical_arrow(tables: dict[str, pa.Table | None], schemas: dict[str, tuple[Column, ...]]) -> dict[str, Any]:
    """The final tables in a row order that depends on their content only.

    Instances by index; probes by (instance, repeat, j); episodes by (instance, repeat), keeping
    the runner's plan order (blind first, then budgets) within a trajectory; the engine cache by
    (engine, instance truth, query, argument). Instances order the others, so ``test-10000``
    follows ``test-9999``. Each table named in ``schemas`` gets every schema column, in schema
    order, then its others (:func:`with_schema_columns`).
    """
    out = dict(tables)
    instances = tables.get("instances")
    if instances is not None and "instance_index" in instances.column_names:
        instances = instances.take(indices(np.argsort(_numpy(instances.column("instance_index")), kind="stable")))
        out["instances"] = instances
    order = instance_order(instances)
    out["probes"] = by_instance(tables.get("probes"), ["instance_id", "repeat", "j"], order)
    out["episodes"] = by_instance(tables.get("episodes"), ["instance_id", "repeat"], order)
    cache = tables.get("engine_cache")
    rows = engine_cache_order(cache) if cache is not None else None
    if rows is not None:
        out["engine_cache"] = cache.take(indices(rows))
    for name, columns in schemas.items():
        if out.get(name) is not None:
            out[name] = with_schema_columns(out[name], columns)
    return {name: out[name] for name in tables}


def instance_order(instances: pa.Table | None) -> dict[str, int]:
    """Each instance id's position in the canonical instance order (by ``instance_index``);
    empty without an instances table that has one."""
    if instances is None or "instance_index" not in instances.column_names:
        return {}
    rows = np.argsort(_numpy(instances.column("instance_index")), kind="stable")
    ids = [str(i) for i in instances.column("instance_id").take(indices(rows)).to_pylist()]
    return {iid: n for n, iid in enumerate(ids)}


def instance_positions(ids: Any, order: dict[str, int]) -> np.ndarray:
    """Each id's position in ``order`` (float); ids it lacks come after every instance.

    ``ids``: an Arrow column or array, or any sequence of ids (a pandas column included).
    """
    values = ids if isinstance(ids, (pa.Array, pa.ChunkedArray)) else pa.array(np.asarray(ids, dtype=object).astype(str))
    if not pa.types.is_large_string(values.type):
        values = values.cast(pa.large_string())
    at = _numpy(pc.index_in(values, value_set=strings(list(order)))).astype(float)
    at[np.isnan(at)] = len(order)  # not in ``order``: after every instance
    return at


def by_instance(table: pa.Table | None, keys: list[str], order: dict[str, int]) -> pa.Table | None:
    """``table`` sorted (stably) by its instances' positions in ``order``, then by ``keys``."""
    if table is None or not table.num_rows or not set(keys) <= set(table.column_names):
        return table
    position = instance_positions(table.column("instance_id"), order) if order else np.zeros(table.num_rows)
    sort_keys = [position, _ranks(table.column("instance_id"))] + [_numpy(table.column(k)) for k in keys[1:]]
    return table.take(indices(np.lexsort(sort_keys[::-1])))


def with_schema_columns(table: pa.Table, columns: tuple[Column, ...]) -> pa.Table:
    """Every schema column, in schema order, then the table's others; a column the table lacks
    (a table of failed rows only lacks some) is added empty (null), as an all-None pandas column
    converts. The pandas metadata names the columns in their new order."""
    present = table.column_names
    if not present:
        return table
    names = [n for c in columns for n in (vector_columns(present, c.name) if c.vector else [c.name]) or [c.name]]
    order = names + [c for c in present if c not in names]
    if order == present:
        return table
    for name in names:
        if name not in present:
            table = table.append_column(name, pa.nulls(table.num_rows))
    return table.select(order).replace_schema_metadata(_metadata_in_order(table.schema.metadata, order))


def _metadata_in_order(metadata: dict[bytes, bytes] | None, order: list[str]) -> dict[bytes, bytes] | None:
    """``metadata`` with its pandas entry's columns in ``order``; a column it does not name is an
    empty one (what ``from_pandas`` records for a column of None)."""
    if not metadata or b"pandas" not in metadata:
        return metadata
    pandas = json.loads(metadata[b"pandas"])
    known = {c["name"]: c for c in pandas["columns"]}
    pandas["columns"] = [known.get(name) or {"name": name, "field_name": name, "pandas_type": "empty",
                                             "numpy_type": "object", "metadata": None} for name in order]
    return {**metadata, b"pandas": json.dumps(pandas).encode("utf8")}


def engine_cache_order(cache: pa.Table) -> np.ndarray | None:
    """Row positions that put an engine cache in its canonical order: by engine, the instance
    truth (the latent columns), query, then argument (as tuples of floats compare); None for a
    table without those columns. The keys alone are converted, not the answers."""
    cols = list(cache.column_names)
    if not cache.num_rows or not {"engine", "query", "arg"} <= set(cols):
        return None
    latents = cols[cols.index("query") + 1: cols.index("arg")]  # the family's latent names
    keys = [_ranks(cache.column("engine")), *(_numpy(cache.column(n)) for n in latents),
            _ranks(cache.column("query")), *_arg_sort_keys(cache.column("arg"))]
    return np.lexsort(keys[::-1])


def _arg_sort_keys(args: pa.ChunkedArray) -> list[np.ndarray]:
    """Sort keys that order query arguments as tuples of floats do: one per component when
    every argument has the same length (read from the list buffers), else the tuples' ranks."""
    matrix = _arrow_float_matrix(args)
    if matrix is None:
        values = args.to_pylist()
        matrix = float_matrix(values)
        if matrix is None:  # arguments of different lengths
            tuples = [tuple(float(v) for v in a) for a in values]
            distinct = sorted(set(tuples))
            rank = {t: n for n, t in enumerate(distinct)}
            return [np.array([rank[t] for t in tuples], dtype=np.int64)]
    return [matrix[:, i] for i in range(matrix.shape[1])]


def _arrow_float_matrix(column: pa.ChunkedArray) -> np.ndarray | None:
    """A list column of float vectors of one length as a ``[rows, length]`` array (None when
    their lengths differ or one is missing), read from its values buffer."""
    column = column.combine_chunks() if column.num_chunks != 1 else column.chunk(0)
    if column.null_count:
        return None
    lengths = _numpy(pc.list_value_length(column))
    if len(lengths) and (lengths != lengths[0]).any():
        return None
    flat = _numpy(pc.list_flatten(column)).astype(float, copy=False)
    return flat.reshape(len(column), -1)


def _ranks(column: pa.ChunkedArray) -> np.ndarray:
    """Each value's rank among the column's distinct values (text in code-point order, as Python
    and pandas compare it): a sort key for :func:`numpy.lexsort`."""
    values = np.asarray(column.to_pylist(), dtype=object)
    return np.unique(values, return_inverse=True)[1].reshape(-1)


def _numpy(column: pa.ChunkedArray | pa.Array) -> np.ndarray:
    """``to_numpy`` of an array or column, read from its buffers where it can (no pandas import)."""
    return to_numpy(column)
