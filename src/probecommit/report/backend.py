"""matplotlib's backend: Agg for commands and scripts, the user's own where they chose one.

The report modules draw off-screen (PNG and PDF files), so they ask for Agg, which needs no
display. A backend the user chose wins: ``MPLBACKEND``, or a Jupyter/IPython session (its
inline backend is what shows ``AuditReport.plot()`` in a notebook).
"""

from __future__ import annotations

import os
import sys

import matplotlib


def use_agg_unless_chosen() -> None:
    """``matplotlib.use("Agg")`` unless ``MPLBACKEND`` is set or this is an IPython/Jupyter session."""
    if os.environ.get("MPLBACKEND") or "ipykernel" in sys.modules or "IPython" in sys.modules:
        return
    matplotlib.use("Agg")
