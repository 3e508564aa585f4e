"""Self-contained HTML audit report: figures embedded as base64 PNG (matplotlib Agg).

Engine-free and runner-free: it takes the results of :mod:`probecommit.audit`
(an audit table, and optionally calibration and gate results) and writes one HTML
file that opens anywhere without its neighbours.
"""

from __future__ import annotations

import base64
import html
import io
import math
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit import __version__  # noqa: E402
from probecommit.audit.io import GROUP_COLUMNS  # noqa: E402


def _label(row: pd.Series | dict, groups: list[str]) -> str:
    return " / ".join(str(row[g]) for g in groups) or "episodes"


def audit_figure(table: pd.DataFrame, nominal: float = 0.8):
    """Per-budget coverage, support escape and optimism with bootstrap bands.

    Args:
        table: Output of :func:`probecommit.audit.metrics.audit_table`.
        nominal: Nominal coverage drawn as a dashed line.

    Returns:
        A matplotlib Figure.
    """
    groups = [g for g in GROUP_COLUMNS if g in table.columns]
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.2), dpi=120)
    panels = (
        (axes[0], (("coverage", "episode"), ("cluster_coverage", "cluster")), "coverage", nominal),
        (axes[1], (("escape", "escape"),), "support escape", None),
        (axes[2], (("optimism", "e_k"),), "optimism $e_k = R_k - \\hat R_k$", 0.0),
    )
    keyed = list(table.groupby(groups, sort=True)) if groups else [((), table)]
    colors = plt.cm.tab10(np.arange(max(len(keyed), 1)) % 10)
    for (key, g), color in zip(keyed, colors):
        key = key if isinstance(key, tuple) else (key,)
        name = " / ".join(map(str, key)) or "episodes"
        g = g.sort_values("k")
        for ax, metrics, _, _ in panels:
            for metric, tag in metrics:
                style = "-" if metric != "cluster_coverage" else "--"
                label = f"{name} ({tag})" if len(metrics) > 1 else name
                marker = "o" if len(g) == 1 else "."
                ax.plot(g["k"], g[metric], style, marker=marker, color=color, label=label)
                ax.fill_between(g["k"], g[f"{metric}_lo"], g[f"{metric}_hi"], color=color, alpha=0.15, lw=0)
    for ax, _, title, ref in panels:
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("budget k")
        if ref is not None:
            ax.axhline(ref, color="grey", ls=":", lw=1)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6, loc="lower left")
    fig.tight_layout()
    return fig


def calibration_figure(table3: pd.DataFrame, nominal: float = 0.8):
    """Original vs calibrated cluster coverage and optimism per budget (Table III)."""
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.0), dpi=120)
    for name, color in (("original", "tab:red"), ("calibrated", "tab:blue")):
        for ax, metric in zip(axes, ("cluster_coverage", "optimism")):
            ax.plot(table3["k"], table3[f"{metric}_{name}"], "o-", color=color, label=name)
            ax.fill_between(table3["k"], table3[f"{metric}_lo_{name}"], table3[f"{metric}_hi_{name}"],
                            color=color, alpha=0.15, lw=0)
    axes[0].axhline(nominal, color="grey", ls=":", lw=1)
    axes[1].axhline(0.0, color="grey", ls=":", lw=1)
    axes[0].set_title("cluster coverage", fontsize=10)
    axes[1].set_title("optimism $e_k$", fontsize=10)
    for ax in axes:
        ax.set_xlabel("budget k")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def gates_figure(result):
    """Failure among committed vs commit rate per gate, and claimed vs realized at the operating point."""
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.3), dpi=120, gridspec_kw={"width_ratios": [3, 2]})
    for name, c in result.curves.groupby("signal", sort=False):
        axes[0].plot(c["commit_rate"], c["failure"], drawstyle="default", lw=1.4,
                     ls="--" if name == "oracle" else "-", label=name)
    axes[0].set_xlabel("commit rate")
    axes[0].set_ylabel("failure among committed")
    axes[0].set_xlim(0, 1)
    axes[0].grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    s = result.summary
    if "claimed" in s.columns:
        x = np.arange(len(s))
        axes[1].bar(x - 0.2, s["claimed"].fillna(0.0), 0.4, color="lightgrey", label="claimed")
        axes[1].bar(x + 0.2, s["realized"], 0.4, color="tab:red", label="realized")
        axes[1].set_xticks(x, s["signal"], rotation=20, fontsize=7)
        axes[1].set_title("at the operating point", fontsize=10)
        axes[1].legend(fontsize=7)
    fig.tight_layout()
    return fig


def figure_to_base64(fig) -> str:
    """PNG bytes of a figure, base64-encoded; the figure is closed."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _fmt(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v))
    if isinstance(v, (float, np.floating)):
        if math.isnan(v):
            return "–"
        if math.isinf(v):
            return "∞" if v > 0 else "−∞"
        return f"{v:.3f}"
    return html.escape(str(v))


def table_html(df: pd.DataFrame, intervals: bool = True) -> str:
    """An HTML table; ``x``, ``x_lo``, ``x_hi`` triples collapse to ``x [lo, hi]``."""
    cols = list(df.columns)
    shown = []
    for c in cols:
        if intervals and (c.endswith("_lo") or c.endswith("_hi")) and c[:-3] in cols:
            continue
        shown.append(c)
    head = "".join(f"<th>{html.escape(c)}</th>" for c in shown)
    body = []
    for _, row in df.iterrows():
        cells = []
        for c in shown:
            text = _fmt(row[c])
            if intervals and f"{c}_lo" in cols and f"{c}_hi" in cols:
                text += f" <span class='ci'>[{_fmt(row[c + '_lo'])}, {_fmt(row[c + '_hi'])}]</span>"
            cells.append(f"<td>{text}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;font-size:12px;margin:0.6em 0}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}th{background:#f3f3f3}
.ci{color:#777;font-size:11px}img{max-width:100%}.note{color:#555;font-size:13px}
"""


def write_html_report(path: str | Path, audit_result=None, *, title: str = "probecommit audit",
                      calibration=None, gates=None, nominal: float = 0.8, notes: str = "") -> Path:
    """Write the self-contained HTML report.

    Args:
        path: Output ``.html`` file.
        audit_result: An :class:`~probecommit.audit.pipeline.AuditResult` (or a
            bare audit table DataFrame).
        title: Page title.
        calibration: Optional ``CalibrationResult``.
        gates: Optional ``GatesResult``.
        nominal: Nominal coverage line.
        notes: Free text shown under the title.

    Returns:
        The written path.
    """
    path = Path(path)
    parts = [f"<h1>{html.escape(title)}</h1>",
             f"<p class='note'>probecommit {__version__}, written "
             f"{datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}. Intervals: cluster bootstrap over "
             "instances (repeats kept together), percentile.</p>"]
    if notes:
        parts.append(f"<p class='note'>{html.escape(notes)}</p>")
    if audit_result is not None:
        table = audit_result if isinstance(audit_result, pd.DataFrame) else audit_result.table
        parts.append("<h2>Audit: coverage, support escape, optimism</h2>")
        if not isinstance(audit_result, pd.DataFrame):
            parts.append(f"<p class='note'>source: {html.escape(str(audit_result.source))}; "
                         f"{audit_result.n_total} rows, {audit_result.n_failed} failed (excluded).</p>")
        parts.append(f"<img alt='audit' src='data:image/png;base64,{figure_to_base64(audit_figure(table, nominal))}'>")
        parts.append(table_html(table))
        surprise = getattr(audit_result, "surprise", None)
        if surprise is not None and len(surprise):
            parts.append("<h3>Prequential surprise: rank AUC for final-budget escape</h3>")
            parts.append(table_html(surprise))
    if calibration is not None:
        c = calibration
        parts.append("<h2>Calibration</h2>")
        thr = ", ".join(f"t<sub>{k}</sub> = {_fmt(v)}" for k, v in c.thresholds.items())
        parts.append(f"<p>1 − α = {1 - c.alpha:.2f}, M = {c.n_calibration} calibration instances. "
                     f"Fixed-budget thresholds: {thr}. Simultaneous t = {_fmt(c.simultaneous_threshold)}. "
                     f"Margin γ = {c.margin.gamma:.2f}{'' if c.margin.satisfied else ' (rule not met on the grid)'}; "
                     f"distribution-free margin {_fmt(c.distribution_free_margin)}.</p>")
        parts.append(f"<img alt='calibration' src='data:image/png;base64,"
                     f"{figure_to_base64(calibration_figure(c.table3, 1 - c.alpha))}'>")
        parts.append(table_html(c.table3))
        parts.append(table_html(pd.DataFrame([c.summary]), intervals=False))
        parts.append(f"<h3>Cost of calibration (failure at k = {c.cost_budget})</h3>")
        parts.append(table_html(c.cost))
        parts.append(table_html(c.cost_differences.rename(columns={"difference": "difference"})))
    if gates is not None:
        parts.append("<h2>Commit gates (first passage over nested budgets)</h2>")
        info = ", ".join(f"{k} = {_fmt(v)}" for k, v in gates.info.items() if not isinstance(v, pd.DataFrame))
        if info:
            parts.append(f"<p class='note'>{info}; {gates.n_trajectories} trajectories, {gates.n_dropped} dropped.</p>")
        parts.append(f"<img alt='gates' src='data:image/png;base64,{figure_to_base64(gates_figure(gates))}'>")
        parts.append(table_html(gates.summary, intervals=False))
        surprise = gates.info.get("surprise")
        if isinstance(surprise, pd.DataFrame) and len(surprise):
            parts.append("<h3>Prequential surprise: rank AUC for final-budget escape</h3>")
            parts.append(table_html(surprise))
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>{''.join(parts)}</body></html>")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(doc, encoding="utf-8")
    return path
