"""The final instances, probes and episodes tables of a run built in Arrow alone, where that
gives the very table the pandas path gives (``RunDir.finalize``).

Why: the pandas path converts every unit's rows to a DataFrame, sorts, reorders and converts
back (~0.1 s of CPU on a 15,360-row run, most of a finalize that is not Parquet encoding). For
tables of plain columns (64-bit ints, floats, bools, strings) whose only missing values are in
float or string columns, that round trip is the identity on the Arrow table (a null float is
NaN in pandas and null again after), so joining the units' tables and taking the canonical row
order gives the same table; its schema metadata (pandas') is what the pandas path gives a
one-row table of it (``rundir.arrow_canonical_tables``). Anything else (tables of different
schemas, nulls in int or bool columns, nested types, missing schema columns, columns out of
schema order) answers None here and takes the pandas path: the files are byte-identical either
way (tested against the pandas path on the same unit tables).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from probecommit.store.schema import Column, vector_columns

#: Column types whose pandas round trip is the identity (with the null rule below).
_PLAIN = (pa.int64(), pa.float64(), pa.bool_(), pa.string(), pa.large_string())
#: Of those, the types whose nulls survive the round trip (NaN in pandas, null again after).
_NULLABLE = (pa.float64(), pa.string(), pa.large_string())
#: The sort keys after the instance of each table ordered by instance (``rundir.canonical_tables``).
KEYS = {"probes": ("repeat", "j"), "episodes": ("repeat",)}


def joined(tables: list[pa.Table], columns: tuple[Column, ...]) -> pa.Table | None:
    """The units' tables of one name joined in unit order, in one chunk per column; None where
    the pandas path could give another table (see the module docstring)."""
    nonempty = [t for t in tables if t.num_rows]
    if not nonempty or any(not t.schema.equals(nonempty[0].schema, check_metadata=True) for t in nonempty[1:]):
        return None
    schema = nonempty[0].schema
    names = schema.names
    wanted = [n for c in columns for n in (vector_columns(names, c.name) if c.vector else [c.name]) or [c.name]]
    if names[:len(wanted)] != wanted or len(set(names)) != len(names):
        return None
    table = pa.concat_tables(nonempty)
    for field, column in zip(schema, table.columns):
        if field.type not in _PLAIN or (column.null_count and field.type not in _NULLABLE):
            return None
        if field.type == pa.float64() and pc.any(pc.is_nan(column)).as_py():  # a NaN comes back null
            return None
    return table


def instance_rank(instances: pa.Table) -> tuple[np.ndarray, dict[str, int]] | None:
    """The rows of the instances table in canonical order (stably by ``instance_index``) and each
    instance id's position in it; None when the table lacks those columns or has nulls there."""
    if not {"instance_index", "instance_id"} <= set(instances.column_names):
        return None
    index, ids = instances.column("instance_index"), instances.column("instance_id")
    if index.null_count or ids.null_count or not pa.types.is_integer(index.type):
        return None
    rows = np.argsort(index.to_numpy(), kind="stable")
    ordered = np.asarray(ids.to_numpy(zero_copy_only=False), dtype=object)[rows]
    return rows, {iid: n for n, iid in enumerate(ordered.tolist())}


def by_instance(table: pa.Table, keys: tuple[str, ...], order: dict[str, int]) -> np.ndarray | None:
    """The rows of ``table`` stably sorted by instance position in ``order`` (ids it lacks after
    every instance, among themselves by id), then id, then ``keys``: what
    ``rundir._by_instance`` sorts by. None when a key is missing or not a null-free int column."""
    if not {"instance_id", *keys} <= set(table.column_names):
        return None
    ids = np.asarray(table.column("instance_id").to_numpy(zero_copy_only=False), dtype=object)
    if table.column("instance_id").null_count:
        return None
    key_arrays = []
    for name in keys:
        column = table.column(name)
        if column.null_count or not pa.types.is_integer(column.type):
            return None
        key_arrays.append(column.to_numpy())
    position = np.array([order.get(i, len(order)) for i in ids.tolist()], dtype=np.int64)
    _, id_codes = np.unique(ids.astype(str), return_inverse=True)  # string order, as pandas sorts str
    # np.lexsort sorts by its last key first and is stable.
    return np.lexsort((*reversed(key_arrays), id_codes.reshape(-1), position))


def taken(table: pa.Table, rows: np.ndarray) -> pa.Table:
    """``table``'s ``rows`` in that order, one chunk per column (the identity taken as is)."""
    if len(rows) == table.num_rows and np.array_equal(rows, np.arange(table.num_rows)):
        return table.combine_chunks()
    return table.take(pa.array(rows, type=pa.int64())).combine_chunks()
