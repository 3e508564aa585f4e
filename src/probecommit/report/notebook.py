"""The plot-first Python API: ``probecommit.audit_run(path)`` and ``probecommit.audit_log(path)``.

Both return an :class:`AuditReport`: the audit's numbers (``.table``, wide, as the
command prints them; ``.to_frame()``, tidy), its figure (``.plot()``, the figure of
``probecommit audit``'s report, a matplotlib Figure) and, in a notebook, a rich
display (the table with intervals and the figure inline), as ArviZ or pandas objects do.
The numbers are those of ``probecommit audit`` with the same resamples and seed.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path

from probecommit.audit.pipeline import AuditResult, audit
from probecommit.audit.stats import DEFAULT_RESAMPLES, DEFAULT_SEED
from probecommit.errors import UserError


class NotARunError(UserError, ValueError):
    """``audit_run`` was given something that is not a run directory (the message says what to use)."""


@dataclass
class AuditReport(AuditResult):
    """An :class:`~probecommit.audit.pipeline.AuditResult` that draws itself.

    Attributes (besides the audit's): ``nominal``, the coverage drawn as a dashed line.
    """

    nominal: float = 0.8

    def plot(self, nominal: float | None = None):
        """The report's figure: coverage, support escape, optimism and failure per budget with
        their intervals, one colour per method (and model variant). Returns the matplotlib Figure
        (closed in pyplot, so a notebook shows it once, as the cell's value)."""
        import matplotlib.pyplot as plt

        from probecommit.report.audit_report import audit_figure

        fig = audit_figure(self.table, self.nominal if nominal is None else nominal)
        plt.close(fig)
        return fig

    def summary(self):
        """The table as ``probecommit audit`` prints it: one row per method (variant) and budget."""
        return self.table

    def _repr_html_(self) -> str:
        from probecommit.report.audit_report import figure_to_base64, table_html

        notes = "".join(f"<p><b>note:</b> {html.escape(n)}</p>" for n in self.notes)
        failed = f"; {self.n_failed} failed row(s) excluded" if self.n_failed else ""
        image = figure_to_base64(self.plot())
        return (f"<div><p><b>probecommit audit</b> of {html.escape(str(self.source))}: {self.n_total} rows{failed}. "
                "Intervals: 95% cluster bootstrap over instances.</p>"
                f"{notes}{table_html(self.table)}"
                f"<img src='data:image/png;base64,{image}' alt='audit figure' style='max-width:100%'/></div>")

    def __repr__(self) -> str:
        groups = [c for c in ("method", "variant") if c in self.table.columns]
        keys = sorted({" / ".join(map(str, r)) for r in self.table[groups].itertuples(index=False)}) if groups else []
        return (f"AuditReport(source={str(self.source)!r}, rows={self.n_total}, failed={self.n_failed}, "
                f"budgets={sorted(self.table['k'].unique().tolist())}, groups={keys})")


def _report(result: AuditResult, nominal: float) -> AuditReport:
    return AuditReport(result.table, result.surprise, result.source, result.n_total, result.n_failed,
                       list(result.notes), nominal=nominal)


def audit_run(path: str | Path, *, resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
              nominal: float = 0.8) -> AuditReport:
    """Audit a run directory (what ``probecommit run``, ``demo`` or ``replay`` wrote).

    Raises:
        NotARunError: ``path`` is not a run directory (for a log, use :func:`audit_log`).
        probecommit.audit.io.EpisodeTableError: the episode table is malformed.
    """
    path = Path(path)
    if not (path.is_dir() and (path / "episodes.parquet").is_file()):
        raise NotARunError(f"{path} is not a run directory (no episodes.parquet); for a CSV/Parquet or "
                           "session log use probecommit.audit_log")
    return _report(audit(path, resamples=resamples, seed=seed), nominal)


def audit_log(path: str | Path, *, resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
              nominal: float = 0.8) -> AuditReport:
    """Audit a log of your own robot: a CSV or Parquet episode table (``docs/record-schema.md``), or a
    ``probecommit.Session`` log (``.jsonl`` or its directory), whose scored episodes are audited.

    Raises:
        probecommit.audit.io.EpisodeTableError: a column is missing or malformed (the message names it).
    """
    path = Path(path)
    if (path.is_file() and path.suffix == ".jsonl") or (path.is_dir() and (path / "session.jsonl").is_file()):
        from probecommit.robot.table import session_episodes

        rows = session_episodes(path).rows
        rows.attrs["source"] = str(path)
        return _report(audit(rows, resamples=resamples, seed=seed), nominal)
    return _report(audit(path, resamples=resamples, seed=seed), nominal)
