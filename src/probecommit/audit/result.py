"""The audit table in tidy (long) form: one row per group, budget and metric, for pandas and plotting.

:func:`probecommit.audit.metrics.audit_table` is wide (``coverage``, ``coverage_lo``,
``coverage_hi``, ``escape``, ... side by side), which reads well as a report table. A
notebook user filters, groups and plots; for that the same numbers are melted into
``method, variant, k, n_episodes, metric, value, lo, hi`` (``lo``/``hi`` NaN for a
metric without an interval). No number is recomputed.
"""

from __future__ import annotations

import pandas as pd

from probecommit.audit.io import GROUP_COLUMNS

#: Metrics in the order a reader meets them; any other numeric column follows.
METRIC_ORDER = ("coverage", "cluster_coverage", "escape", "realized", "predicted", "optimism")
#: Columns that describe a row rather than measure it.
_ID_COLUMNS = (*GROUP_COLUMNS, "k", "n_episodes", "n_failed", "n_instances", "n_repeats")


def tidy(table: pd.DataFrame) -> pd.DataFrame:
    """The wide audit ``table`` as one row per (group, k, metric) with ``value``, ``lo``, ``hi``."""
    ids = [c for c in _ID_COLUMNS if c in table.columns]
    cols = set(table.columns)
    bounds = {c for c in cols if (c.endswith("_lo") or c.endswith("_hi")) and c[:-3] in cols}
    metrics = [m for m in METRIC_ORDER if m in cols]
    metrics += [c for c in table.columns if c not in ids and c not in bounds and c not in metrics
                and pd.api.types.is_numeric_dtype(table[c])]
    parts = []
    for metric in metrics:
        part = table[ids].copy()
        part["metric"] = metric
        part["value"] = table[metric].astype(float)
        part["lo"] = table[f"{metric}_lo"].astype(float) if f"{metric}_lo" in cols else float("nan")
        part["hi"] = table[f"{metric}_hi"].astype(float) if f"{metric}_hi" in cols else float("nan")
        parts.append(part)
    if not parts:
        return pd.DataFrame(columns=[*ids, "metric", "value", "lo", "hi"])
    return pd.concat(parts, ignore_index=True).sort_values([*[c for c in GROUP_COLUMNS if c in ids], "metric", "k"],
                                                           kind="stable").reset_index(drop=True)
