"""Read and validate probe tables: our run directories' ``probes.parquet`` and a user's log.

A probe table has one row per probe: ``instance_id, repeat, j, u, y``
(``store.schema.PROBE_COLUMNS``). Replays rebuild belief traces from it, so a
malformed table must be refused with ONE message naming the column and the first
offending row, never reshaped into wrong numbers. Rows are 0-based data rows; for
CSV input the file line (header = line 1) is given too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa

from probecommit.store.schema import PROBE_COLUMNS, checked_frame, component_names
from probecommit.errors import UserError

#: Required columns of a scalar-probe, scalar-observation table (insertion).
REQUIRED = tuple(c.name for c in PROBE_COLUMNS)
KEY_COLUMNS = ("instance_id", "repeat", "j")
_NA_TEXT = {"", "nan", "NaN", "NA", "N/A", "null", "None", "none"}


class ProbeTableError(UserError, ValueError):
    """A probe table that cannot be replayed; the message names the column and row."""


def _where(row: int, csv: bool) -> str:
    return f"row {row} (CSV line {row + 2})" if csv else f"row {row}"


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _numbers(df: pd.DataFrame, name: str, source: str, csv: bool) -> np.ndarray:
    col = df[name]
    if pd.api.types.is_bool_dtype(col):
        raise ProbeTableError(f"{source}: column '{name}' must be numeric, found booleans")
    if pd.api.types.is_numeric_dtype(col):
        values = col.to_numpy(dtype=float, na_value=np.nan)
    else:
        text = col.astype(object)
        bad_type = text.map(lambda v: isinstance(v, (bool, np.bool_)) or not isinstance(v, (str, int, float, np.number)) and v is not None)
        values = pd.to_numeric(
            text.map(lambda v: np.nan if v is None or (isinstance(v, str) and v.strip() in _NA_TEXT) else v)
            .where(~bad_type, np.nan),
            errors="coerce",
        ).to_numpy(dtype=float)
        given = ~text.map(lambda v: v is None or (isinstance(v, float) and np.isnan(v))
                          or (isinstance(v, str) and v.strip() in _NA_TEXT)).to_numpy(bool)
        unparsed = (np.isnan(values) & given) | bad_type.to_numpy(bool)
        if unparsed.any():
            row = int(np.flatnonzero(unparsed)[0])
            raise ProbeTableError(f"{source}: column '{name}' must be numeric, found {_shown(text.iloc[row])} "
                                  f"at {_where(row, csv)}")
    bad = ~np.isfinite(values)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        kind = "is empty or NaN" if np.isnan(values[row]) else "is infinite"
        raise ProbeTableError(f"{source}: column '{name}' {kind} at {_where(row, csv)} "
                              f"({int(bad.sum())} row(s) affected)")
    return values


def _integers(df: pd.DataFrame, name: str, lowest: int, source: str, csv: bool) -> np.ndarray:
    values = _numbers(df, name, source, csv)
    frac = values != np.round(values)
    if frac.any():
        row = int(np.flatnonzero(frac)[0])
        raise ProbeTableError(f"{source}: column '{name}' must be an integer, found {_shown(df[name].iloc[row])} "
                              f"at {_where(row, csv)}")
    low = values < lowest
    if low.any():
        row = int(np.flatnonzero(low)[0])
        raise ProbeTableError(f"{source}: column '{name}' must be >= {lowest}, found {_shown(df[name].iloc[row])} "
                              f"at {_where(row, csv)}")
    if np.any(values > 2**53):
        row = int(np.flatnonzero(values > 2**53)[0])
        raise ProbeTableError(f"{source}: column '{name}' is implausibly large at {_where(row, csv)}")
    return values.astype(np.int64)


def _is_empty_id(value: object) -> bool:
    return value is None or (isinstance(value, float) and np.isnan(value)) or str(value).strip() in ("", "nan", "None")


def _normal_id(value: object) -> str:
    return str(int(value)) if isinstance(value, float) and value == int(value) else str(value).strip()


def _instance_ids(column: pd.Series, source: str, csv: bool) -> np.ndarray:
    """The ``instance_id`` column as ``str`` objects, refused where one is empty.

    A table of text ids (Parquet, CSV) is checked and normalized once per distinct id: a log
    holds many probes of few instances, and a Python string per row would be made for nothing.
    Other columns (a frame built by hand, of numbers or mixed objects) are checked row by row.
    """
    if isinstance(column.dtype, pd.StringDtype):
        codes, uniques = pd.factorize(column)
        values = np.append(np.asarray(uniques, dtype=object), None)  # a missing id's code, -1, reads None
    else:
        values = column.astype(object).to_numpy()
        codes = np.arange(values.size)
    empty = np.array([_is_empty_id(v) for v in values], dtype=bool)[codes]
    if empty.any():
        row = int(np.flatnonzero(empty)[0])
        raise ProbeTableError(f"{source}: column 'instance_id' is empty at {_where(row, csv)}")
    return np.array([_normal_id(v) for v in values], dtype=object)[codes]


def validate_probes(table: pd.DataFrame, source: str = "probe table", *, csv: bool = False,
                    instance_ids: pd.Series | None = None, probe_dim: int = 1,
                    observation_dim: int = 1) -> pd.DataFrame:
    """Validate a probe table and return its normalized copy.

    Checks: the key columns and every probe and observation component column
    (``u``/``y``, or ``u_0..``/``y_0..`` for vectors; ``store.schema.component_names``)
    exist once each; ``instance_id`` is non-empty; ``repeat``
    is an integer >= 0 and ``j`` an integer >= 1; ``u`` and ``y`` are finite numbers;
    no probe is given twice; every trajectory holds probes ``1..K`` with no gap and
    the same ``K``; and, if ``instance_ids`` is given, every instance is known.

    Returns:
        The table with ``instance_id`` as str, ``repeat``/``j`` as int64, ``u``/``y``
        as float64, rows in their original order.

    Raises:
        ProbeTableError: with one line naming the problem, the column and the first row.
    """
    values = component_names("u", probe_dim) + component_names("y", observation_dim)
    df = checked_frame(table, KEY_COLUMNS + tuple(values), source, ProbeTableError, "a probe table")
    out = pd.DataFrame({
        "instance_id": _instance_ids(df["instance_id"], source, csv),
        "repeat": _integers(df, "repeat", 0, source, csv),
        "j": _integers(df, "j", 1, source, csv),
        **{name: _numbers(df, name, source, csv) for name in values},
    })
    dup = out.duplicated(["instance_id", "repeat", "j"]).to_numpy()
    if dup.any():
        row = int(np.flatnonzero(dup)[0])
        raise ProbeTableError(f"{source}: probe j={out['j'].iloc[row]} of instance {out['instance_id'].iloc[row]!r} "
                              f"repeat {out['repeat'].iloc[row]} is given twice (again at {_where(row, csv)})")
    if instance_ids is not None:
        unknown = ~out["instance_id"].isin(set(instance_ids.astype(str))).to_numpy()
        if unknown.any():
            row = int(np.flatnonzero(unknown)[0])
            raise ProbeTableError(f"{source}: instance {out['instance_id'].iloc[row]!r} at {_where(row, csv)} "
                                  "is not in the instances table")
    groups = out.groupby(["instance_id", "repeat"], sort=False)["j"]
    count, top = groups.transform("size").to_numpy(), groups.transform("max").to_numpy()
    gap = count != top
    if gap.any():
        row = int(np.flatnonzero(gap)[0])
        raise ProbeTableError(f"{source}: trajectory of instance {out['instance_id'].iloc[row]!r} repeat "
                              f"{out['repeat'].iloc[row]} has {count[row]} probe(s) but j goes up to {top[row]}; "
                              f"probes must be numbered 1..K with no gap (see {_where(row, csv)})")
    k = int(np.bincount(top).argmax())
    ragged = top != k
    if ragged.any():
        row = int(np.flatnonzero(ragged)[0])
        raise ProbeTableError(f"{source}: trajectory of instance {out['instance_id'].iloc[row]!r} repeat "
                              f"{out['repeat'].iloc[row]} has {top[row]} probe(s) but most have {k}; "
                              f"every trajectory needs the same number of probes (see {_where(row, csv)})")
    return out


def read_probes(path: str | Path, instance_ids: pd.Series | None = None, probe_dim: int = 1,
                observation_dim: int = 1) -> pd.DataFrame:
    """Read and validate a probe table: a run directory, a Parquet file or a CSV log.

    Raises:
        ProbeTableError: unreadable file or a malformed table (see :func:`validate_probes`).
    """
    path = Path(path)
    if path.is_dir():
        path = path / "probes.parquet"
    if not path.is_file():
        raise ProbeTableError(f"no probe table at {path}")
    suffix = path.suffix.lower()
    try:
        if suffix in (".parquet", ".pq"):
            frame, csv = pd.read_parquet(path), False
        elif suffix in (".csv", ".txt"):
            frame, csv = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True), True
        else:
            raise ProbeTableError(f"unsupported probe table format {path.suffix!r} for {path}; use .parquet or .csv")
    except ProbeTableError:
        raise
    except (OSError, ValueError, UnicodeDecodeError, pa.ArrowException) as exc:
        first = " ".join(str(exc).split())[:200]
        raise ProbeTableError(f"cannot read probe table {path}: {first}") from None
    return validate_probes(frame, str(path), csv=csv, instance_ids=instance_ids, probe_dim=probe_dim,
                           observation_dim=observation_dim)
