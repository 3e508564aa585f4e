"""One figure style for every figure: the paper's column widths and fonts of at least 7 pt.

A figure is drawn at its printed size (3.5 in for one column, 7.16 in for two), so fonts
set here are the fonts a reader sees; :func:`probecommit.report.figures.save_figure`
writes PNG (300 dpi) and PDF.
"""

from __future__ import annotations

import matplotlib

from probecommit.report.backend import use_agg_unless_chosen  # noqa: E402

use_agg_unless_chosen()

#: One IEEE column and the full text width (inches).
COLUMN = 3.5
DOUBLE = 7.16
#: Smallest font size anywhere on a figure (points).
MIN_FONT = 7

RC = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "legend.title_fontsize": 7,
    "figure.titlesize": 8,
    "lines.linewidth": 1.2,
    "lines.markersize": 3.5,
    "axes.linewidth": 0.6,
    "savefig.dpi": 300,
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.02,
    "pdf.fonttype": 42,  # embed TrueType: editable text in the PDF
}


def apply() -> None:
    """Set the style (idempotent; called by every figure module on import)."""
    matplotlib.rcParams.update(RC)


apply()


def integer_ticks(axis) -> None:
    """Ticks at whole numbers only on an integer axis (a budget k has no tick at 2.5).

    ``axis`` is ``ax.xaxis`` or ``ax.yaxis``.
    """
    from matplotlib.ticker import MaxNLocator

    axis.set_major_locator(MaxNLocator(integer=True))


def legend_above(ax_or_fig, handles=None, labels=None, ncol: int = 3, **kwargs):
    """A frameless legend above the axes (or figure), off the data."""
    from matplotlib.figure import Figure

    if handles is None:
        target = ax_or_fig.axes[0] if isinstance(ax_or_fig, Figure) else ax_or_fig
        handles, labels = target.get_legend_handles_labels()
    anchor = kwargs.pop("bbox_to_anchor", (0.5, 1.0))
    return ax_or_fig.legend(handles, labels, loc="lower center", bbox_to_anchor=anchor, ncol=ncol, frameon=False,
                            handlelength=1.6, columnspacing=1.0, borderaxespad=0.2, **kwargs)


def text_sizes(fig, drawn: bool = False) -> list[tuple[float, str]]:
    """``(size in pt, text)`` of every visible, non-empty Text artist of ``fig`` (titles,
    labels, tick labels, legends, annotations), as drawn after a layout pass.

    ``drawn``: the caller has just drawn ``fig`` (a ``savefig``), so its tick labels are
    placed and the draw here is skipped: a whole draw of the figure, about as dear as the
    ``savefig`` itself (docs/decisions.md, "cal4:").
    """
    from matplotlib.text import Text

    if not drawn:
        fig.canvas.draw()
    return [(t.get_fontsize(), t.get_text()) for t in fig.findobj(Text)
            if t.get_visible() and t.get_text().strip() and t.get_figure() is not None]


def placed_sizes(fig, placed_width: float) -> list[tuple[float, str]]:
    """Font sizes as a reader sees them when the figure is scaled to ``placed_width`` inches."""
    scale = placed_width / float(fig.get_size_inches()[0])
    return [(size * scale, text) for size, text in text_sizes(fig)]
