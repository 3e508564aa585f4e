"""Arrow arrays and pandas metadata of a run's columns, built without importing pandas.

pyarrow 26 imports pandas the first time it builds an array from anything (``pa.array`` on a
float64 NumPy array, a list of strings or of floats: its pandas shim asks whether the input is a
pandas object), and a run's process spent about 0.2 s of CPU on that import (issue 42, target 2;
docs/decisions.md, "run: ..."). So the columns of a unit's tables are built here from their
buffers (``pa.Array.from_buffers``), as ``pa.array(value, from_pandas=True)`` builds them (NaN
and None are null; strings are large strings), and the pandas metadata a one-row DataFrame of
the column would give is written by hand. Anything outside the kinds handled here (say an
object column mixing types) returns None, and the caller takes the pandas route, as before:
``tests/runner/test_rundir.py`` holds both routes equal, types and metadata included.
"""

from __future__ import annotations

import json
from importlib import metadata as _metadata
from typing import Any

import numpy as np
import pyarrow as pa

#: The NumPy dtypes built from their buffers, by kind and size (others take the pandas route).
_NUMERIC = {np.dtype(np.float64): pa.float64(), np.dtype(np.float32): pa.float32(),
            np.dtype(np.int64): pa.int64(), np.dtype(np.int32): pa.int32()}


def _validity(valid: np.ndarray) -> tuple[pa.Buffer | None, int]:
    """The validity bitmap of ``valid`` (None when nothing is null) and the null count."""
    nulls = int(valid.size - np.count_nonzero(valid))
    if not nulls:
        return None, 0
    return pa.py_buffer(np.packbits(valid, bitorder="little")), nulls


def _numeric(values: np.ndarray) -> pa.Array:
    """A float or integer array; NaN is null (``from_pandas``)."""
    values = np.ascontiguousarray(values)
    bitmap, nulls = _validity(~np.isnan(values)) if values.dtype.kind == "f" else (None, 0)
    return pa.Array.from_buffers(_NUMERIC[values.dtype], len(values), [bitmap, pa.py_buffer(values)], null_count=nulls)


def _booleans(values: np.ndarray) -> pa.Array:
    data = pa.py_buffer(np.packbits(np.ascontiguousarray(values, dtype=bool), bitorder="little"))
    return pa.Array.from_buffers(pa.bool_(), len(values), [None, data])


def _strings(values: list) -> pa.Array:
    """Large strings of ``values`` (``str`` or None, None null)."""
    n = len(values)
    nulls = None in values
    present = [v for v in values if v is not None] if nulls else values
    text = "".join(present)
    if text.isascii():  # a character is a byte: lengths without encoding each value
        lengths, data = np.fromiter(map(len, present), np.int64, len(present)), text.encode("ascii")
    else:
        encoded = [v.encode("utf-8") for v in present]
        lengths, data = np.fromiter(map(len, encoded), np.int64, len(present)), b"".join(encoded)
    valid = np.fromiter((v is not None for v in values), bool, n) if nulls else np.ones(n, dtype=bool)
    sizes = np.zeros(n, dtype=np.int64)
    sizes[valid] = lengths
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    bitmap, null_count = _validity(valid)
    buffers = [bitmap, pa.py_buffer(offsets), pa.py_buffer(data)]
    return pa.Array.from_buffers(pa.large_string(), n, buffers, null_count=null_count)


def _float_lists(values: list) -> pa.Array | None:
    """``list<double>`` of lists of finite floats (None otherwise: NaN inside a list is left to pyarrow)."""
    lengths = np.fromiter(map(len, values), np.int64, len(values))
    flat = [x for v in values for x in v]
    if not all(type(x) is float or type(x) is np.float64 for x in flat):  # a float32 would make list<float>
        return None
    inner = np.array(flat, dtype=np.float64)
    if not np.isfinite(inner).all():
        return None
    offsets = np.zeros(len(values) + 1, dtype=np.int32)
    np.cumsum(lengths, out=offsets[1:])
    return pa.ListArray.from_arrays(_offsets(offsets), _numeric(inner))


def _offsets(offsets: np.ndarray) -> pa.Array:
    return pa.Array.from_buffers(pa.int32(), len(offsets), [None, pa.py_buffer(offsets)])


def _python_values(values: list) -> pa.Array | None:
    """An object column or a list, by the one kind of value it holds (None alongside any);
    None when it mixes kinds (pyarrow's inference then decides)."""
    kinds = set(map(type, values)) - {type(None)}
    if not kinds:
        return pa.nulls(len(values))
    if kinds == {str}:
        return _strings(values)
    if kinds == {list} and None not in values:
        return _float_lists(values)
    if kinds <= {float, np.float64}:
        return _numeric(np.array([np.nan if v is None else v for v in values], dtype=np.float64))
    if None in values:
        return None
    if kinds <= {int, np.int64}:
        return _numeric(np.array(values, dtype=np.int64))
    if kinds <= {bool, np.bool_}:
        return _booleans(np.array(values, dtype=bool))
    return None


def column_array(value: Any, n_rows: int) -> pa.Array | None:
    """``value`` (a 1-D NumPy array or list of ``n_rows`` values, or a scalar, broadcast) as
    ``pa.array(value, from_pandas=True)`` gives it, strings as large strings; None when it is
    of a kind not handled here."""
    if not isinstance(value, (list, np.ndarray)):
        value = np.broadcast_to(np.asarray(value), (n_rows,))
        if value.dtype.kind == "U":
            value = value.astype(object)
    if isinstance(value, list):
        return _python_values(value)
    if value.dtype in _NUMERIC:
        return _numeric(value)
    if value.dtype.kind == "b":
        return _booleans(value)
    if value.dtype.kind in "UO":
        return _python_values(value.tolist())
    return None


def _pandas_types(value: Any, array: pa.Array) -> tuple[str, str] | None:
    """``pandas_type`` and ``numpy_type`` of the column ``value`` in the metadata of a one-row
    DataFrame of its first value (how the metadata was always made); None when not known here."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "fiub":
        name = value.dtype.name
        return ("bool", "bool") if value.dtype.kind == "b" else (name, name)
    first = value[0] if isinstance(value, (list, np.ndarray)) else value
    if isinstance(value, np.ndarray) and value.dtype.kind == "O" and not (first is None or isinstance(first, str)):
        return None  # pandas keeps an object array's dtype: only strings (and None) are read as pandas 3 reads them
    if isinstance(first, np.generic):
        first = first.item()
    if first is None:
        return "empty", "object"
    if isinstance(first, str):
        return "object", "str"
    if type(first) is bool:
        return "bool", "bool"
    if type(first) in (int, float):
        return ("int64", "int64") if type(first) is int else ("float64", "float64")
    if isinstance(first, list) and pa.types.is_list(array.type) and pa.types.is_float64(array.type.value_type):
        return "list[float64]", "object"
    return None


def _pandas_version() -> str | None:
    """The installed pandas' version, read from its distribution (no import); None without one."""
    try:
        return _metadata.version("pandas")
    except _metadata.PackageNotFoundError:
        return None


_VERSION: list[str | None] = []


def pandas_metadata(columns: dict[str, Any], arrays: list[pa.Array]) -> dict[bytes, bytes] | None:
    """The schema metadata ``pa.Schema.from_pandas`` writes for a one-row DataFrame of the
    columns' first values, written by hand for pandas 3 (whose metadata this follows); None when
    a column is of a kind not handled here, or the installed pandas is not 3.x."""
    if not _VERSION:
        _VERSION.append(_pandas_version())
    version = _VERSION[0]
    if version is None or not version.startswith("3."):
        return None
    entries = []
    for (name, value), array in zip(columns.items(), arrays):
        types = _pandas_types(value, array)
        if types is None or not isinstance(name, str):
            return None
        entries.append({"name": name, "field_name": name, "pandas_type": types[0], "numpy_type": types[1],
                        "metadata": None})
    meta = {"index_columns": [], "column_indexes": [], "columns": entries, "attributes": {},
            "creator": {"library": "pyarrow", "version": pa.__version__}, "pandas_version": version}
    return {b"pandas": json.dumps(meta).encode("utf8")}


def strings(values: list) -> pa.Array:
    """Large strings of ``values`` (``str`` or None), built as :func:`column_array` builds them."""
    return _strings(list(values))


def indices(positions: np.ndarray) -> pa.Array:
    """Row positions as an Arrow ``int64`` array for ``take`` (``take`` of a NumPy array converts it
    through ``pa.array``, which imports pandas)."""
    return _numeric(np.asarray(positions, dtype=np.int64))


def _chunk(column: pa.Array | pa.ChunkedArray) -> pa.Array:
    if isinstance(column, pa.Array):
        return column
    return column.chunk(0) if column.num_chunks == 1 else column.combine_chunks()


def to_numpy(column: pa.Array | pa.ChunkedArray) -> np.ndarray:
    """A column as ``to_numpy(zero_copy_only=False)`` gives it, read from its buffers for numbers
    (nulls as NaN, integers with nulls as floats) and booleans without nulls; other columns
    through pyarrow's own conversion (which imports pandas)."""
    array = _chunk(column)
    kind = array.type
    if pa.types.is_boolean(kind) and not array.null_count:
        bits = np.unpackbits(np.frombuffer(array.buffers()[1], dtype=np.uint8), bitorder="little")
        return bits[array.offset:array.offset + len(array)].astype(bool)
    if not (pa.types.is_integer(kind) or pa.types.is_floating(kind)) or pa.types.is_float16(kind):
        return array.to_numpy(zero_copy_only=False)
    values = np.frombuffer(array.buffers()[1], dtype=kind.to_pandas_dtype(), count=len(array), offset=array.offset *
                           kind.bit_width // 8)
    if not array.null_count:
        return values
    bits = np.unpackbits(np.frombuffer(array.buffers()[0], dtype=np.uint8), bitorder="little")
    out = values.astype(np.float64 if pa.types.is_integer(kind) else values.dtype)
    out[~bits[array.offset:array.offset + len(array)].astype(bool)] = np.nan
    return out
