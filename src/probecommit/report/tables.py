"""Plain per-budget summaries of an episode table (point estimates)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

if TYPE_CHECKING:
    import pandas as pd
    import pyarrow as pa

#: The order methods are listed in (others after them: see :func:`budget_rows`).
METHOD_ORDER = {"blind_bayes": 0, "blind_robust": 1, "probe_robust": 2}
SUMMARY_COLUMNS = ("method", "k", "episodes", "failure", "predicted", "optimism", "coverage", "escape", "failed")
#: The summary's means and the episode column each averages.
MEANS = {"failure": "realized", "predicted": "predicted", "coverage": "covered", "escape": "escaped"}


def budget_summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """:func:`budget_rows` as a DataFrame (one row per (method, k)), for the report and the demo's reading."""
    import pandas as pd

    dtypes = {"method": episodes["method"].dtype, "k": episodes["k"].dtype, "episodes": "int64", "failed": "int64"}
    frame = pd.DataFrame(budget_rows(summary_columns(episodes)), columns=list(SUMMARY_COLUMNS))
    return frame.astype({**dtypes, **{c: "float64" for c in (*MEANS, "optimism")}})


def summary_columns(episodes: pa.Table | pd.DataFrame) -> dict[str, np.ndarray]:
    """The columns :func:`budget_rows` reads, as NumPy arrays: ``method`` and ``status`` as objects (missing:
    None), ``k`` as stored (integers with a missing value as floats, NaN), the averaged ones as floats (missing:
    NaN). From a run's Arrow table without importing pandas (``probecommit run`` prints its summary from it;
    docs/decisions.md, "run: ..."), or from a DataFrame."""
    if not hasattr(episodes, "column_names"):
        k = episodes["k"]
        columns = {n: episodes[n].to_numpy(dtype=object, na_value=None) for n in ("method", "status")}
        columns["k"] = k.to_numpy(dtype=float, na_value=np.nan) if k.isna().any() else k.to_numpy()
        return columns | {c: episodes[c].to_numpy(dtype=float, na_value=np.nan) for c in MEANS.values()}
    from probecommit.store.arrow_columns import to_numpy

    columns = {n: np.array(episodes.column(n).to_pylist(), dtype=object) for n in ("method", "status")}
    columns["k"] = to_numpy(episodes.column("k"))
    return columns | {c: _arrow_floats(episodes.column(c)) for c in MEANS.values()}


def _arrow_floats(column: pa.ChunkedArray) -> np.ndarray:
    """An Arrow column as floats, nulls NaN: numbers and booleans without nulls from their buffers, the
    rest (booleans with nulls: a failed rollout's row has no ``covered``) from Python values, as pyarrow's
    own conversion would import pandas."""
    import pyarrow as pa

    kind = column.type
    if pa.types.is_integer(kind) or pa.types.is_floating(kind) or (pa.types.is_boolean(kind) and not column.null_count):
        from probecommit.store.arrow_columns import to_numpy

        return to_numpy(column).astype(float)
    return np.array([np.nan if v is None else v for v in column.to_pylist()], dtype=float)


def budget_rows(columns: Mapping[str, np.ndarray]) -> list[dict[str, Any]]:
    """Per (method, k): ok episodes, failure, mean predicted, optimism, episode coverage, support escape
    and failed episodes (status != ok, a missing status included), as plain Python values, in NumPy.

    What pandas' grouped means gave, kept (``tests/report/test_budget_rows.py`` holds the two equal): a row
    with a missing method or k is in no group; a mean skips missing values (NaN when a group has none); a
    (method, k) with failed episodes only has no row. The order: the methods of :data:`METHOD_ORDER` first, in
    its order, each by k; then every other method by name, each by k (pandas' sort gave those all NaN, a tie,
    and so listed them by k first, a method's rows apart). NumPy's means sum pairwise, pandas' with
    compensation: they may differ in the last bits (within 1e-12; printed to three digits, and no published
    key is computed here).
    """
    method, k, status = columns["method"], columns["k"], columns["status"]
    keyed = np.fromiter((m is not None for m in method), bool, len(method)) & (k == k)
    ok = keyed & (status == "ok")
    failed = keyed & ~ok
    pairs = set(zip(method[ok].tolist(), k[ok].tolist()))
    is_method = {m: method == m for m in {m for m, _ in pairs}}
    rows = []
    for m, budget in sorted(pairs, key=lambda p: (METHOD_ORDER.get(p[0], len(METHOD_ORDER)), p[0], p[1])):
        group = is_method[m] & (k == budget)
        at = ok & group
        row = {"method": m, "k": budget, "episodes": int(np.count_nonzero(at))}
        row.update({name: _mean(columns[source][at]) for name, source in MEANS.items()})
        row.update(optimism=row["failure"] - row["predicted"], failed=int(np.count_nonzero(failed & group)))
        rows.append({c: row[c] for c in SUMMARY_COLUMNS})
    return rows


def _mean(values: np.ndarray) -> float:
    """The mean of the values that are not NaN (NaN when none is), as pandas' grouped mean skips them."""
    present = values[~np.isnan(values)]
    return float(np.mean(present)) if present.size else float("nan")


def to_markdown(table: pd.DataFrame, digits: int = 3) -> str:
    cols = list(table.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for _, row in table.iterrows():
        cells = []
        for c in cols:
            v = row[c]
            cells.append(f"{v:+.{digits}f}" if c == "optimism" else f"{v:.{digits}f}" if isinstance(v, float) else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
