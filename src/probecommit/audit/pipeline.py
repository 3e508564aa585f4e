"""The two-condition audit of an episode table: a run directory, a user's log, or a frame.

Tables only: this module never re-runs inference. Calibration and commit gates,
which re-commit episodes under new thresholds and margins, live on the runner side
(``probecommit.runner.calibration``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from probecommit.audit.io import group_columns, ok_episodes, read_episodes, validate_episodes
from probecommit.audit.metrics import audit_table
from probecommit.audit.stats import DEFAULT_LEVEL, DEFAULT_RESAMPLES, DEFAULT_SEED, few_clusters_note
from probecommit.audit.surprise import surprise_auc

logger = logging.getLogger(__name__)

#: The executor's method whose episodes the surprise AUC reads.
PROBE_METHOD = "probe_robust"


# ----------------------------------------------------------------------------- audit


@dataclass
class AuditResult:
    """The two-condition audit of one episode table.

    Attributes:
        table: Per (method, variant, k) metrics with intervals (:func:`audit_table`).
        surprise: Surprise AUC for final-budget escape per budget (probe method
            only; None when the table has no ``max_surprise``).
        source: Where the table came from.
        n_total: Rows read.
        n_failed: Failed rows (excluded from every metric).
    """

    table: pd.DataFrame
    surprise: pd.DataFrame | None
    source: str
    n_total: int
    n_failed: int
    notes: list[str] = field(default_factory=list)

    def to_frame(self) -> pd.DataFrame:
        """The audit table in tidy form: one row per (method, variant, k, metric) with ``value``, ``lo``,
        ``hi`` (:func:`probecommit.audit.result.tidy`)."""
        from probecommit.audit.result import tidy

        return tidy(self.table)


def audit(path_or_table: str | Path | pd.DataFrame, *, resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
          level: float = DEFAULT_LEVEL, loss: str | None = None) -> AuditResult:
    """Audit a run directory, a user's Parquet/CSV log, or an in-memory table.

    Args:
        path_or_table: What to audit.
        resamples: Cluster-bootstrap resamples.
        seed: Bootstrap seed.
        level: Interval level.
        loss: ``"binary"`` or ``"continuous"`` (None: inferred; see ``audit.io.validate_episodes``).

    Returns:
        The audit result.

    Raises:
        EpisodeTableError: The table is malformed (the message says how).
    """
    if isinstance(path_or_table, pd.DataFrame):
        df = validate_episodes(path_or_table, loss=loss)
    else:
        df = read_episodes(path_or_table, loss=loss)
    table = audit_table(df, resamples=resamples, seed=seed, level=level)
    surprise = None
    probe = ok_episodes(df)
    probe = probe.loc[probe["k"] >= 1]
    if "method" in probe.columns:
        probe = probe.loc[probe["method"] == PROBE_METHOD]
    if "max_surprise" in probe.columns and probe["max_surprise"].notna().any():
        groups = group_columns(probe)
        parts = []
        for key, g in (probe.groupby(groups) if groups else [((), probe)]):
            key = key if isinstance(key, tuple) else (key,)
            part = surprise_auc(g, resamples=resamples, seed=seed, level=level)
            for name, value in zip(groups, key):
                part.insert(0, name, value)
            parts.append(part)
        surprise = pd.concat(parts, ignore_index=True) if parts else None
    logger.info("audited %s: %d rows (%d failed, excluded), %d resamples", df.attrs.get("source", "a table"),
                df.attrs.get("n_total", len(df)), df.attrs.get("n_failed", 0), resamples)
    notes = list(df.attrs.get("notes", []))
    if len(table):
        few = few_clusters_note(int(table["n_instances"].min()))
        if few:
            notes.append(few)
    return AuditResult(table, surprise, df.attrs.get("source", "table"), df.attrs.get("n_total", len(df)),
                       df.attrs.get("n_failed", 0), notes)
