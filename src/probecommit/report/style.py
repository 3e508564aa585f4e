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
