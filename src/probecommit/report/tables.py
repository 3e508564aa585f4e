"""Plain per-budget summaries of an episode table (point estimates)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pandas as pd
    import pyarrow as pa

#: The order methods are listed in (others after them, by name).
METHOD_ORDER = {"blind_bayes": 0, "blind_robust": 1, "probe_robust": 2}
SUMMARY_COLUMNS = ("method", "k", "episodes", "failure", "predicted", "optimism", "coverage", "escape", "failed")


def budget_summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """Per (method, k): failure, mean predicted, optimism, episode coverage, support escape.

    Failed episodes (status != ok) are excluded and counted in ``failed``.
    """
    import pandas as pd

    ok = episodes[episodes["status"] == "ok"]
    grouped = ok.groupby(["method", "k"], sort=True)
    table = pd.DataFrame(
        {
            "episodes": grouped.size(),
            "failure": grouped["realized"].mean(),
            "predicted": grouped["predicted"].mean(),
            "coverage": grouped["covered"].mean(),
            "escape": grouped["escaped"].mean(),
        }
    )
    table["optimism"] = table["failure"] - table["predicted"]
    failed = episodes[episodes["status"] != "ok"].groupby(["method", "k"]).size()
    table["failed"] = failed.reindex(table.index).fillna(0).astype(int)
    table = table.reset_index()
    table = table.sort_values(["method", "k"], key=lambda s: s.map(METHOD_ORDER) if s.name == "method" else s)
    return table[list(SUMMARY_COLUMNS)]


def budget_rows(episodes: pa.Table) -> list[dict[str, Any]] | None:
    """:func:`budget_summary`'s rows (dicts), computed with NumPy from a run's final episodes table
    as Arrow: what ``probecommit run`` prints, without converting the table to a DataFrame (which
    imports pandas; docs/decisions.md, "run: ..."). The means are NumPy's; pandas' grouped means
    sum with compensation, so ``predicted`` and ``optimism`` may differ in the last bits (printed to
    three digits). None for a table with failed rows, missing values or methods of other names: :func:`budget_summary` then.
    """
    from probecommit.store.arrow_columns import to_numpy

    names = ("method", "k", "status", "realized", "predicted", "covered", "escaped")
    if not set(names) <= set(episodes.column_names) or any(episodes.column(n).null_count for n in names):
        return None
    method = np.asarray(episodes.column("method").to_pylist(), dtype=object)
    if not set(method.tolist()) <= set(METHOD_ORDER) or not all(s == "ok" for s in episodes.column("status").to_pylist()):
        return None  # another method: where pandas' sort puts it is left to pandas
    k = to_numpy(episodes.column("k"))
    values = {name: to_numpy(episodes.column(source)).astype(float) for name, source in
              (("failure", "realized"), ("predicted", "predicted"), ("coverage", "covered"), ("escape", "escaped"))}
    rows = []
    for m in sorted(set(method.tolist()), key=METHOD_ORDER.__getitem__):
        for budget in sorted(set(k[method == m].tolist())):
            at = (method == m) & (k == budget)
            row = {"method": m, "k": budget, "episodes": int(at.sum())}
            row.update({name: float(np.mean(column[at])) for name, column in values.items()})
            rows.append({**row, "optimism": row["failure"] - row["predicted"], "failed": 0})
    return [{c: row[c] for c in SUMMARY_COLUMNS} for row in rows]


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
