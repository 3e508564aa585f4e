"""Plain per-budget summaries of an episode table (point estimates)."""

from __future__ import annotations

import pandas as pd


def budget_summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """Per (method, k): failure, mean predicted, optimism, episode coverage, support escape.

    Failed episodes (status != ok) are excluded and counted in ``failed``.
    """
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
    order = {"blind_bayes": 0, "blind_robust": 1, "probe_robust": 2}
    table = table.reset_index()
    table = table.sort_values(["method", "k"], key=lambda s: s.map(order) if s.name == "method" else s)
    return table[["method", "k", "episodes", "failure", "predicted", "optimism", "coverage", "escape", "failed"]]


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
