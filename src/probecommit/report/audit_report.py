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

from probecommit.report.backend import use_agg_unless_chosen  # noqa: E402

use_agg_unless_chosen()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit import __version__  # noqa: E402
from probecommit.report.style import DOUBLE  # noqa: E402
from probecommit.audit.io import GROUP_COLUMNS  # noqa: E402
from probecommit.store.safefile import write_text


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
    fig, axes = plt.subplots(2, 2, figsize=(DOUBLE, 5.0))
    axes = axes.ravel()
    panels = (
        (axes[0], (("coverage", "episode"), ("cluster_coverage", "cluster")), "coverage", nominal),
        (axes[1], (("escape", "escape"),), "support escape", None),
        (axes[2], (("optimism", "e_k"),), "optimism $e_k = R_k - \\hat R_k$", 0.0),
        (axes[3], (("realized", "realized"), ("predicted", "predicted")), "failure (or miss): realized vs predicted", None),
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
                if metric == "predicted":
                    style = ":"
                ax.plot(g["k"], g[metric], style, marker=marker, color=color, label=label)
                if f"{metric}_lo" in g.columns:
                    ax.fill_between(g["k"], g[f"{metric}_lo"], g[f"{metric}_hi"], color=color, alpha=0.15, lw=0)
    for ax, _, title, ref in panels:
        ax.set_title(title)
        ax.set_xlabel("budget k")
        if ref is not None:
            ax.axhline(ref, color="grey", ls=":", lw=1)
        ax.grid(alpha=0.3)
    # One legend below the panels: colours name the method / variant; line styles the metric.
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=color, marker="o", ms=3, label=" / ".join(map(str, key if isinstance(key, tuple) else (key,))) or "episodes")
               for (key, _), color in zip(keyed, colors)]
    handles += [Line2D([], [], color="0.3", ls="-", label="episode coverage / realized"),
                Line2D([], [], color="0.3", ls="--", label="cluster coverage"),
                Line2D([], [], color="0.3", ls=":", label="predicted"),
                Line2D([], [], color="grey", ls=":", lw=1, label=f"nominal {nominal:.2f} (coverage), 0 (optimism)")]
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.legend(handles=handles, loc="lower center", ncol=3, frameon=False)
    return fig


def calibration_figure(table3: pd.DataFrame, nominal: float = 0.8):
    """Original vs calibrated cluster coverage and optimism per budget (Table III)."""
    fig, axes = plt.subplots(1, 2, figsize=(DOUBLE, 2.4))
    for name, color in (("original", "tab:red"), ("calibrated", "tab:blue")):
        for ax, metric in zip(axes, ("cluster_coverage", "optimism")):
            ax.plot(table3["k"], table3[f"{metric}_{name}"], "o-", color=color, label=name)
            ax.fill_between(table3["k"], table3[f"{metric}_lo_{name}"], table3[f"{metric}_hi_{name}"],
                            color=color, alpha=0.15, lw=0)
    axes[0].axhline(nominal, color="grey", ls=":", lw=1, label=f"nominal {nominal:.2f}")
    axes[1].axhline(0.0, color="grey", ls=":", lw=1)
    axes[0].set_title("cluster coverage")
    axes[1].set_title("optimism $e_k$")
    for ax in axes:
        ax.set_xlabel("budget k")
        ax.grid(alpha=0.3)
    axes[0].legend(frameon=False)
    fig.tight_layout()
    return fig


def gates_figure(result):
    """Failure among committed vs commit rate per gate, and claimed vs realized at the operating point."""
    fig, axes = plt.subplots(1, 2, figsize=(DOUBLE, 2.6), gridspec_kw={"width_ratios": [3, 2]})
    for name, c in result.curves.groupby("signal", sort=False):
        if name == "oracle":
            # The hindsight oracle commits the successes first: zero failure up to its commit
            # rate, then each further commit is a failure. Drawn as the step it is.
            c = c.sort_values("commit_rate")
            axes[0].step(c["commit_rate"], c["failure"], where="post", lw=1.2, ls="--", color="k", label="oracle (hindsight)")
            continue
        axes[0].plot(c["commit_rate"], c["failure"], lw=1.2, label=name)
    axes[0].set_xlabel("commit rate")
    axes[0].set_ylabel("failure among committed")
    axes[0].set_xlim(0, 1)
    axes[0].grid(alpha=0.3)
    axes[0].legend(frameon=False)
    s = result.summary
    if "claimed" in s.columns:
        x = np.arange(len(s))
        axes[1].bar(x - 0.2, s["claimed"].fillna(0.0), 0.4, color="lightgrey", label="claimed")
        axes[1].bar(x + 0.2, s["realized"], 0.4, color="tab:red", label="realized")
        axes[1].set_xticks(x, s["signal"], rotation=20)
        axes[1].set_title("at the operating point")
        axes[1].legend(frameon=False)
    fig.tight_layout()
    return fig


def figure_to_base64(fig) -> str:
    """PNG bytes of a figure, base64-encoded; the figure is closed."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=150)
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
    head = "".join(f"<th>{html.escape(HEADERS.get(c, c.replace('_', ' ')))}</th>" for c in shown)
    body = []
    for _, row in df.iterrows():
        cells = []
        for c in shown:
            text = _fmt(row[c])
            if intervals and f"{c}_lo" in cols and f"{c}_hi" in cols:
                text += f" <span class='ci'>[{_fmt(row[c + '_lo'])}, {_fmt(row[c + '_hi'])}]</span>"
            cells.append(f"<td>{text}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return (f"<div class='scroll'><table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table></div>")


#: Table headers as a reader says them.
HEADERS = {
    "k": "budget k", "n_episodes": "episodes", "n_instances": "instances", "n_repeats": "repeats", "n_failed": "failed",
    "coverage": "episode coverage", "cluster_coverage": "cluster coverage", "escape": "support escape",
    "realized": "realized Rₖ", "predicted": "predicted R̂ₖ", "optimism": "optimism eₖ", "n_escaped": "escaped", "n_covered": "not escaped",
    "auc": "rank AUC", "method": "method", "variant": "model variant", "threshold": "threshold t_k",
}

#: Fewer clusters than this make intervals (and AUCs) too coarse to read as evidence.
FEW_CLUSTERS = 20

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1100px;margin:1.5em auto;padding:0 0.8em;color:#222;line-height:1.4}
.scroll{overflow-x:auto;-webkit-overflow-scrolling:touch;max-width:100%}
table{border-collapse:collapse;font-size:13px;margin:0.6em 0;white-space:nowrap}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}th{background:#f3f3f3;position:sticky;top:0}
.ci{color:#666;font-size:12px}img{max-width:100%;height:auto}.note{color:#555;font-size:14px}
.warn{background:#fff4e5;border-left:4px solid #f0a020;padding:0.5em 0.8em;margin:0.8em 0}
@media (max-width:600px){body{margin:0.5em auto}h1{font-size:1.3em}table{font-size:12px}}
"""


def _warnings(table: pd.DataFrame, audit_result: Any) -> list[str]:
    """Plain warnings when the data are too thin for the intervals to mean much."""
    out = []
    n_clusters = None
    for col in ("n_instances", "n_episodes"):
        if col in table.columns and len(table):
            n_clusters = int(table[col].max())
            break
    if n_clusters is not None and n_clusters < FEW_CLUSTERS:
        out.append(f"Only {n_clusters} episodes or instances per budget: bootstrap intervals over so few clusters are "
                   "too coarse to be evidence (an interval of zero width here does not mean certainty).")
    surprise = getattr(audit_result, "surprise", None)
    if isinstance(surprise, pd.DataFrame) and len(surprise) and "n_escaped" in surprise.columns:
        few = int(surprise["n_escaped"].max())
        if few < 10:
            out.append(f"At most {few} escaped episodes: the surprise AUC rests on too few escapes to read.")
    for note in getattr(audit_result, "notes", []) or []:
        out.append(note)
    return out


def write_html_report(path: str | Path, audit_result=None, *, title: str = "probecommit audit",
                      calibration=None, gates=None, nominal: float = 0.8, notes: str = "",
                      images: list[tuple[str, Path]] | None = None) -> Path:
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
        images: ``(caption, png path)`` pairs embedded after the audit (e.g. a belief snapshot).

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
        for text in _warnings(table, audit_result):
            parts.append(f"<div class='warn'>{html.escape(text)}</div>")
        parts.append(f"<img alt='audit: coverage, escape, optimism, realized vs predicted per budget' "
                     f"src='data:image/png;base64,{figure_to_base64(audit_figure(table, nominal))}'>")
        parts.append(table_html(table))
        surprise = getattr(audit_result, "surprise", None)
        if surprise is not None and len(surprise):
            parts.append("<h3>Prequential surprise: rank AUC for final-budget escape</h3>")
            parts.append(table_html(surprise))
    for caption, image in images or []:
        data = base64.b64encode(Path(image).read_bytes()).decode("ascii")
        parts.append(f"<h3>{html.escape(caption)}</h3><img alt='{html.escape(caption)}' src='data:image/png;base64,{data}'>")
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
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'>"
           "<meta name='viewport' content='width=device-width, initial-scale=1'>"
           f"<title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>{''.join(parts)}</body></html>")
    write_text(path, doc)
    return path
