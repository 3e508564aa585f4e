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
from typing import Any, Sequence

import matplotlib

from probecommit.report.backend import use_agg_unless_chosen  # noqa: E402

use_agg_unless_chosen()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit import __version__  # noqa: E402
from probecommit.report import vocabulary as V  # noqa: E402
from probecommit.report.style import COLUMN, DOUBLE, integer_ticks, legend_above  # noqa: E402
from probecommit.audit.io import GROUP_COLUMNS  # noqa: E402
from probecommit.store.safefile import write_text


def _label(row: pd.Series | dict, groups: list[str]) -> str:
    return " / ".join(str(row[g]) for g in groups) or "episodes"


#: Display names of the commit-gate signals (figures and tables).
SIGNAL_NAMES = {"raw": "raw fraction", "adjusted": "adjusted score", "posterior_variance": "posterior variance",
                "oracle": "oracle (hindsight)"}
#: Gate curves: one colour and line style per signal; the oracle long-dashed black.
SIGNAL_STYLES = {"raw": ("C0", "-"), "adjusted": ("C1", (0, (5, 1.5, 1, 1.5))), "posterior_variance": ("C2", (0, (1, 1))),
                 "oracle": ("k", (0, (6, 3)))}


def _group_key(key) -> tuple:
    return key if isinstance(key, tuple) else (key,)


def audit_figure(table: pd.DataFrame, nominal: float = 0.8, width: float = DOUBLE):
    """Per-budget coverage, support escape, optimism and realized vs predicted, with bootstrap bands.

    Drawn at ``width`` inches (the page width by default; :data:`COLUMN` stacks the panels)
    with every label in the paper's words (:mod:`probecommit.report.vocabulary`).

    Args:
        table: Output of :func:`probecommit.audit.metrics.audit_table`.
        nominal: Nominal coverage drawn as a dotted line.
        width: Figure width in inches.

    Returns:
        A matplotlib Figure.
    """
    groups = [g for g in GROUP_COLUMNS if g in table.columns]
    narrow = width < DOUBLE - 0.1
    fig, axes = plt.subplots(4 if narrow else 2, 1 if narrow else 2, figsize=(width, 6.4 if narrow else 4.6))
    axes = axes.ravel()
    panels = (
        (axes[0], (("coverage", "-"), ("cluster_coverage", "--")), "(a) coverage", V.AXIS["coverage"], nominal),
        (axes[1], (("escape", "-"),), "(b) support escape", V.AXIS["escape"], None),
        (axes[2], (("optimism", "-"),), "(c) optimism", "optimism eₖ", 0.0),
        (axes[3], (("realized", "-"), ("predicted", ":")), "(d) realized Rₖ and predicted R̂ₖ", "failure rate", None),
    )
    keyed = list(table.groupby(groups, sort=True)) if groups else [((), table)]
    colors = plt.cm.tab10(np.arange(max(len(keyed), 1)) % 10)
    for (key, g), color in zip(keyed, colors):
        g = g.sort_values("k")
        for ax, metrics, _, _, _ in panels:
            for metric, style in metrics:
                if metric not in g.columns:
                    continue
                ax.plot(g["k"], g[metric], style, marker="o" if len(g) == 1 else ".", color=color)
                if f"{metric}_lo" in g.columns:
                    ax.fill_between(g["k"], g[f"{metric}_lo"], g[f"{metric}_hi"], color=color, alpha=0.15, lw=0)
    for ax, _, title, ylabel, ref in panels:
        ax.set_title(title, loc="left")
        ax.set_xlabel(V.AXIS["k"])
        ax.set_ylabel(ylabel)
        integer_ticks(ax.xaxis)
        if ref is not None:
            ax.axhline(ref, color="grey", ls=":", lw=1)
        ax.grid(alpha=0.3)
    # One legend above the panels: colours name the method / variant; line styles the metric.
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=color, marker="o", ms=3, label=" / ".join(map(V.value_name, _group_key(key))) or "episodes")
               for (key, _), color in zip(keyed, colors)]
    handles += [Line2D([], [], color="0.3", ls="-", label="coverage / realized Rₖ"),
                Line2D([], [], color="0.3", ls="--", label="cluster coverage"),
                Line2D([], [], color="0.3", ls=":", label="predicted R̂ₖ"),
                Line2D([], [], color="grey", ls=":", lw=1, label=f"nominal {nominal:.2f}; optimism 0")]
    rows = -(-len(handles) // (2 if narrow else 3))
    top = 1 - (0.16 * rows + 0.1) / fig.get_size_inches()[1]
    fig.tight_layout(rect=(0, 0, 1, top))
    fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, top), ncol=2 if narrow else 3, frameon=False)
    return fig


def calibration_figure(table3: pd.DataFrame, nominal: float = 0.8, width: float = COLUMN):
    """Original vs calibrated cluster coverage and optimism per budget (the calibration table)."""
    fig, axes = plt.subplots(1, 2, figsize=(width, 2.3))
    for name, color in (("original", "tab:red"), ("calibrated", "tab:blue")):
        for ax, metric in zip(axes, ("cluster_coverage", "optimism")):
            ax.plot(table3["k"], table3[f"{metric}_{name}"], "o-", color=color, label=name)
            ax.fill_between(table3["k"], table3[f"{metric}_lo_{name}"], table3[f"{metric}_hi_{name}"],
                            color=color, alpha=0.15, lw=0)
    axes[0].axhline(nominal, color="grey", ls=":", lw=1, label=f"nominal {nominal:.2f}")
    axes[1].axhline(0.0, color="grey", ls=":", lw=1)
    axes[0].set_ylabel(V.AXIS["cluster_coverage"])
    axes[1].set_ylabel("optimism eₖ")
    for ax in axes:
        ax.set_xlabel(V.AXIS["k"])
        integer_ticks(ax.xaxis)
        ax.grid(alpha=0.3)
    fig.tight_layout(rect=(0, 0, 1, 0.86))
    legend_above(fig, *axes[0].get_legend_handles_labels(), bbox_to_anchor=(0.5, 0.86))
    return fig


def draw_gate_curves(ax, curves: pd.DataFrame, legend: bool = True) -> None:
    """Failure among committed against commit rate, one curve per signal; the oracle dashed, as a step."""
    for name, c in curves.groupby("signal", sort=False):
        color, ls = SIGNAL_STYLES.get(name, ("0.4", "-"))
        c = c.sort_values("commit_rate")
        if name == "oracle":
            # The hindsight oracle commits the successes first: zero failure up to its commit
            # rate, then each further commit is a failure. Drawn as the step it is.
            ax.step(c["commit_rate"], c["failure"], where="post", lw=1.2, ls=ls, color=color, label=SIGNAL_NAMES[name])
            continue
        ax.plot(c["commit_rate"], c["failure"], lw=1.2, ls=ls, color=color, label=SIGNAL_NAMES.get(name, name))
    ax.set_xlabel("commit rate (fraction of episodes)")
    ax.set_ylabel("failure among committed")
    ax.set_xlim(0, 1)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    if legend:
        legend_above(ax, ncol=2)


def draw_gate_operating_point(ax, summary: pd.DataFrame, legend: bool = True) -> None:
    """Mean predicted score at commit (pale) against realized failure (solid), per signal.

    Posterior variance makes no probability claim: its predicted bar is absent, not zero.
    """
    x = np.arange(len(summary))
    names = [SIGNAL_NAMES.get(s, str(s)).replace(" (hindsight)", "") for s in summary["signal"]]
    colors = [SIGNAL_STYLES.get(s, ("0.4", "-"))[0] for s in summary["signal"]]
    if "claimed" in summary.columns:
        claimed = summary["claimed"].to_numpy(float)
        ax.bar(x - 0.2, np.nan_to_num(claimed), 0.4, color=colors, alpha=0.35, label="predicted R̂ₖ (pale)")
    ax.bar(x + 0.2, summary["realized"], 0.4, color=colors, label="realized Rₖ (solid)")
    ax.set_xticks(x, [n.replace(" ", "\n", 1) for n in names])
    ax.set_ylabel("failure at commit")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3, axis="y")
    if legend:
        from matplotlib.patches import Patch

        ax.legend(handles=[Patch(color="0.45", alpha=0.35, label="predicted R̂ₖ"), Patch(color="0.45", label="realized Rₖ")],
                  loc="upper right", ncol=1, frameon=False)  # the bars grow from the left; this corner stays empty


def gates_figure(result, width: float = COLUMN):
    """Failure among committed vs commit rate per gate (top), and predicted vs realized at the operating point."""
    fig, axes = plt.subplots(2, 1, figsize=(width, 4.4), gridspec_kw={"height_ratios": [3, 2]})
    draw_gate_curves(axes[0], result.curves)
    axes[0].set_title("(a) failure among committed", loc="left", pad=28)
    if "realized" in result.summary.columns:
        draw_gate_operating_point(axes[1], result.summary)
        axes[1].set_title("(b) at the operating point", loc="left")
    else:
        axes[1].set_visible(False)
    fig.tight_layout()
    return fig


def figure_to_base64(fig) -> str:
    """PNG bytes of a figure, base64-encoded; the figure is closed."""
    return _figure_png(fig)[0]


#: Resolution of figures embedded in HTML.
HTML_DPI = 150
#: Smallest figure text on screen (CSS px): an image is never shown so small that its text falls below this.
MIN_SCREEN_PX = 9


def _figure_png(fig) -> tuple[str, float | None]:
    """(base64 PNG, smallest text in image pixels); the figure is closed."""
    from probecommit.report.style import text_sizes

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=HTML_DPI)
    sizes = [size for size, _ in text_sizes(fig, drawn=True)]  # as the PNG's draw left them: no second draw
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii"), (min(sizes) * HTML_DPI / 72 if sizes else None)


def img_tag(data: str, alt: str, min_font_px: float | None, narrow: tuple[str, float | None] | None = None,
            dpi: float = HTML_DPI) -> str:
    """An embedded PNG that keeps its smallest text at least :data:`MIN_SCREEN_PX` CSS px.

    The image gets a ``min-width`` (in its scrolling container, the page never scrolls
    sideways) from its natural width and the size of its smallest text; ``narrow``
    (base64, min font px) is a phone layout served below 600 px. ``data-min-font-px``
    lets the browser test measure the text as shown.
    """
    from PIL import Image

    def least(b64: str) -> int:  # the narrowest width (CSS px) at which the image's smallest text stays legible
        return math.ceil(Image.open(io.BytesIO(base64.b64decode(b64))).size[0] * MIN_SCREEN_PX / min_font_px)

    # never shown larger than at HTML_DPI (a column figure is not blown up to the page's width)
    natural = Image.open(io.BytesIO(base64.b64decode(data))).size[0]
    style = f"--maxw:{math.ceil(natural * HTML_DPI / dpi)}px"
    if min_font_px:  # custom properties: the phone layout's own minimum applies where its source does (CSS below)
        style += f";--minw:{least(data)}px" + (f";--minw-narrow:{least(narrow[0])}px" if narrow else "")
    style = f" style='{style}'"
    attr = f" data-min-font-px='{min_font_px:.2f}'" if min_font_px else ""
    img = f"<img alt='{html.escape(alt)}'{attr}{style} src='data:image/png;base64,{data}'>"
    if narrow is None:
        return img
    return f"<picture><source media='(max-width: 600px)' srcset='data:image/png;base64,{narrow[0]}'>{img}</picture>"


def figure_html(fig, alt: str, narrow_fig=None) -> str:
    """A figure (and optionally its phone layout) as a scrolling ``<div class='fig'>`` block."""
    data, px = _figure_png(fig)
    narrow = _figure_png(narrow_fig) if narrow_fig is not None else None
    if narrow is not None and narrow[1] and px:
        px = min(px, narrow[1])
    return f"<div class='fig'>{img_tag(data, alt, px, narrow)}</div>"


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


#: Count columns: whole numbers printed as integers (60, not 60.000).
COUNT_COLUMNS = {"k", "taps", "episodes", "instances", "clusters", "repeats", "failed", "positions", "in_window", "entered",
                 "covered", "escaped_committed", "escaped_rejected", "n_committed", "n_rejected"}


def _integer_columns(df: pd.DataFrame) -> set[str]:
    """Columns printed as integers: integer dtype, or counts (``COUNT_COLUMNS``, ``n_*``) whose values are whole."""
    out = set()
    for c in df.columns:
        if pd.api.types.is_bool_dtype(df[c]) or not pd.api.types.is_numeric_dtype(df[c]):
            continue
        if pd.api.types.is_integer_dtype(df[c]):
            out.add(c)
            continue
        values = df[c].dropna().to_numpy(float)
        count = c in COUNT_COLUMNS or c.startswith("n_")
        if count and len(values) and np.all(np.isfinite(values)) and np.all(values == np.round(values)):
            out.add(c)
    return out


def _bounds(c: str, cols: list[str]) -> tuple[str, str] | None:
    """The interval columns of ``c``: ``c_lo``/``c_hi``, or ``m_lo_arm``/``m_hi_arm`` for ``c = m_arm``."""
    if f"{c}_lo" in cols and f"{c}_hi" in cols:
        return f"{c}_lo", f"{c}_hi"
    if "_" in c:
        m, arm = c.rsplit("_", 1)
        if f"{m}_lo_{arm}" in cols and f"{m}_hi_{arm}" in cols:
            return f"{m}_lo_{arm}", f"{m}_hi_{arm}"
    return None


def table_html(df: pd.DataFrame, intervals: bool = True) -> str:
    """An HTML table in the paper's words; ``x``, ``x_lo``, ``x_hi`` triples collapse to ``x [lo, hi]``.

    Key columns (budget, method, variant, the audit metrics) come first, so they are in view
    at 1280 px; below 600 px each row stacks into label: value lines (``data-label``).
    """
    cols = list(df.columns)
    bounds = {c: _bounds(c, cols) for c in cols} if intervals else {}
    hidden = {b for pair in bounds.values() if pair for b in pair}
    shown = [c for c in cols if c not in hidden]
    shown = [c for c in V.KEY_COLUMNS if c in shown] + [c for c in shown if c not in V.KEY_COLUMNS]
    integers = _integer_columns(df)
    names = {c: HEADERS.get(c, V.html_name(c)) for c in shown}
    head = "".join(f"<th class='{'key' if c in V.KEY_COLUMNS else ''}'>{html.escape(names[c])}</th>" for c in shown)
    body = []
    for _, row in df.iterrows():
        cells = []
        for c in shown:
            value = row[c]
            if c in integers and not pd.isna(value):
                text = str(int(value))
            elif isinstance(value, str) or c in ("method", "variant", "signal"):
                text = html.escape(V.value_name(value))
            else:
                text = _fmt(value)
            if bounds.get(c):
                lo, hi = bounds[c]
                text += f" <span class='ci'>[{_fmt(row[lo])}, {_fmt(row[hi])}]</span>"
            key = " class='key'" if c in V.KEY_COLUMNS else ""
            cells.append(f"<td{key} data-label='{html.escape(names[c])}'>{text}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return (f"<div class='scroll'><table class='stack'><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody>"
            "</table></div>")


#: Table headers as a reader says them.
HEADERS = {
    "k": "budget k", "n_episodes": "episodes", "n_instances": "instances", "n_repeats": "repeats", "n_failed": "failed",
    "coverage": "episode coverage", "cluster_coverage": "cluster coverage", "escape": "support escape",
    "realized": V.HTML["realized"], "predicted": V.HTML["predicted"], "optimism": V.HTML["optimism"], "n_escaped": "escaped", "n_covered": "not escaped",
    "auc": "rank AUC", "method": "method", "variant": "model variant", "threshold": "threshold tₖ",
}

#: Fewer clusters than this make intervals (and AUCs) too coarse to read as evidence.
FEW_CLUSTERS = V.MIN_CLUSTERS

_CSS = """
html{background:#fff}body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1200px;margin:1.5em auto;padding:0 0.8em;color:#222;line-height:1.4}
.scroll{overflow-x:auto;-webkit-overflow-scrolling:touch;max-width:100%}
table{border-collapse:collapse;font-size:13px;margin:0.6em 0;white-space:nowrap}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}th{background:#f3f3f3;position:sticky;top:0}
.ci{color:#666;font-size:12px;display:block}img{max-width:100%;height:auto}.note{color:#555;font-size:14px}
.warn{background:#fff4e5;border-left:4px solid #f0a020;padding:0.5em 0.8em;margin:0.8em 0}
.fig{overflow-x:auto;-webkit-overflow-scrolling:touch;max-width:100%}.fig img{width:100%;display:block;max-width:var(--maxw,100%);min-width:var(--minw,0)}
table td.wrap{white-space:normal;min-width:12em;text-align:left}
@media (max-width:600px){body{margin:0.5em auto}h1{font-size:1.3em}table{font-size:13px}
 .fig img{min-width:var(--minw-narrow,var(--minw,0))}
 table.stack,table.stack tbody,table.stack tr,table.stack td{display:block;white-space:normal}
 table.stack thead{position:absolute;left:-9999px;top:-9999px}
 table.stack tr{border:1px solid #ccc;margin:0 0 0.6em;padding:0.2em 0}
 table.stack td{border:none;border-bottom:1px solid #eee;text-align:right;padding:2px 6px;position:relative;padding-left:45%;min-height:1.2em}
 table.stack td::before{content:attr(data-label);position:absolute;left:6px;width:42%;text-align:left;font-weight:600;white-space:normal}}
"""


def _warnings(table: pd.DataFrame, audit_result: Any) -> list[str]:
    """Plain warnings when the data are too thin for the intervals to mean much."""
    out = []
    n_clusters = None
    for col in ("n_instances", "n_episodes"):
        if col in table.columns and len(table):
            n_clusters = int(table[col].min())
            break
    if n_clusters is not None and n_clusters < FEW_CLUSTERS:
        out.append(f"Intervals here rest on {n_clusters} clusters, fewer than {FEW_CLUSTERS}: a cluster bootstrap over so "
                   "few is too coarse to be evidence (an interval of zero width does not mean certainty).")
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
                      images: list[tuple[str, Path]] | None = None,
                      tables: list[tuple[str, pd.DataFrame]] | None = None, warnings: list[str] | None = None,
                      sections: Sequence[str] = ()) -> Path:
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
        tables: ``(heading, table)`` pairs shown after the images (e.g. a robot session's per-budget table).
        warnings: Extra warnings shown under the title (e.g. too few positions for the intervals).
        sections: HTML already rendered, placed after the sections above (``probecommit calibrate`` draws
            :func:`audit_section_html` and :func:`calibration_section_html` in helper processes).

    Returns:
        The written path.
    """
    path = Path(path)
    parts = _header_html(title, notes, warnings)
    if audit_result is not None:
        parts += audit_section_html(audit_result, nominal)
    parts += _extras_html(images, tables)
    if calibration is not None:
        parts += calibration_section_html(calibration)
    if gates is not None:
        parts += _gates_html(gates)
    parts += sections
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'>"
           "<meta name='viewport' content='width=device-width, initial-scale=1'>"
           f"<title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>{''.join(parts)}</body></html>")
    write_text(path, doc)
    return path


# One function per section of the report: each section is optional (an audit alone, a calibration, the gates),
# and each reads as the part of the page it writes.


def _header_html(title: str, notes: str, warnings: list[str] | None) -> list[str]:
    """The title, the version and date line with the interval convention, the notes and the caller's warnings."""
    parts = [f"<h1>{html.escape(title)}</h1>",
             f"<p class='note'>probecommit {__version__}, written "
             f"{datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}. Intervals: cluster bootstrap over "
             "instances (repeats kept together), percentile.</p>"]
    if notes:
        parts.append(f"<p class='note'>{html.escape(notes)}</p>")
    for text in warnings or []:
        parts.append(f"<div class='warn'>{html.escape(text)}</div>")
    return parts


def audit_section_html(audit_result, nominal: float) -> list[str]:
    """The audit: its source and row counts (an ``AuditResult``; a bare table has none), its warnings,
    figure and table, and the surprise AUCs when the audit computed them."""
    table = audit_result if isinstance(audit_result, pd.DataFrame) else audit_result.table
    parts = ["<h2>Audit: coverage, support escape, optimism</h2>"]
    if not isinstance(audit_result, pd.DataFrame):
        parts.append(f"<p class='note'>source: {html.escape(str(audit_result.source))}; "
                     f"{audit_result.n_total} rows, {audit_result.n_failed} failed (excluded).</p>")
    for text in _warnings(table, audit_result):
        parts.append(f"<div class='warn'>{html.escape(text)}</div>")
    parts.append(figure_html(audit_figure(table, nominal), "audit: coverage, support escape, optimism, realized vs "
                             "predicted per budget", audit_figure(table, nominal, width=COLUMN)))
    parts.append(table_html(table))
    surprise = getattr(audit_result, "surprise", None)
    if surprise is not None and len(surprise):
        parts.append("<h3>Prequential surprise: rank AUC for final-budget escape</h3>")
        parts.append(table_html(surprise))
    return parts


def _extras_html(images: list[tuple[str, Path]] | None, tables: list[tuple[str, pd.DataFrame]] | None) -> list[str]:
    """The caller's images (embedded as data, so the page stays one self-contained file) and tables."""
    parts = []
    for caption, image in images or []:
        from probecommit.report.figures import min_font_px

        data = base64.b64encode(Path(image).read_bytes()).decode("ascii")
        parts.append(f"<h3>{html.escape(caption)}</h3><div class='fig'>{img_tag(data, caption, min_font_px(image))}</div>")
    for heading, frame in tables or []:
        parts.append(f"<h2>{html.escape(heading)}</h2>")
        parts.append(table_html(frame))
    return parts


def calibration_section_html(c, figure=None) -> list[str]:
    """A ``CalibrationResult``: its thresholds and margins in one line, Table III and the cost of calibration.
    ``figure``: its calibration figure when the caller has drawn it already (saved to files: the same
    figure, not built and laid out again; the page's PNG is drawn from it)."""
    parts = ["<h2>Calibration</h2>"]
    thr = ", ".join(f"t<sub>{k}</sub> = {_fmt(v)}" for k, v in c.thresholds.items())
    parts.append(f"<p>1 − α = {1 - c.alpha:.2f}, M = {c.n_calibration} calibration instances. "
                 f"Fixed-budget thresholds: {thr}. Simultaneous t = {_fmt(c.simultaneous_threshold)}. "
                 f"Margin γ = {c.margin.gamma:.2f}{'' if c.margin.satisfied else ' (rule not met on the grid)'}; "
                 f"distribution-free margin {_fmt(c.distribution_free_margin)}.</p>")
    figure = calibration_figure(c.table3, 1 - c.alpha) if figure is None else figure
    parts.append(figure_html(figure, "calibration: cluster coverage and optimism per budget"))
    parts.append(table_html(c.table3))
    parts.append(table_html(pd.DataFrame([c.summary]), intervals=False))
    parts.append(f"<h3>Cost of calibration (failure at k = {c.cost_budget})</h3>")
    parts.append(table_html(c.cost))
    parts.append(table_html(c.cost_differences.rename(columns={"difference": "difference"})))
    return parts


def _gates_html(gates) -> list[str]:
    """A ``GatesResult``: its settings, the failure-vs-commit-rate figure and summary, and its surprise AUCs."""
    parts = ["<h2>Commit gates (first passage over nested budgets)</h2>"]
    info = ", ".join(f"{k} = {_fmt(v)}" for k, v in gates.info.items() if not isinstance(v, pd.DataFrame))
    if info:
        parts.append(f"<p class='note'>{info}; {gates.n_trajectories} trajectories, {gates.n_dropped} dropped.</p>")
    parts.append(figure_html(gates_figure(gates), "commit gates: failure among committed vs commit rate"))
    parts.append(table_html(gates.summary, intervals=False))
    surprise = gates.info.get("surprise")
    if isinstance(surprise, pd.DataFrame) and len(surprise):
        parts.append("<h3>Prequential surprise: rank AUC for final-budget escape</h3>")
        parts.append(table_html(surprise))
    return parts
