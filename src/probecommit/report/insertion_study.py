"""The insertion study (``studies.insertion``) drawn with the report's tables and figures.

``probecommit reproduce insertion`` runs :func:`reproduce_insertion`; the study itself computes,
and this module hands it the report layer's renderers (studies sit below report).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.report.insertion_tables import RENDERERS
from probecommit.report.study_figures import decision_figure, draw_decisive_tap, fault_signatures, scan_figure
from probecommit.studies import insertion
from probecommit.studies.protocol import DEFAULT_PROTOCOL

#: The report's renderers of the insertion study's tables and figures.
RENDER = insertion.Render(tables=RENDERERS, scan_figure=scan_figure, fault_signatures=fault_signatures,
                          decisive_tap_figure=draw_decisive_tap, decision_figure=decision_figure)


def reproduce_insertion(root: str | Path, quick: bool = False, protocol_path: str | Path = DEFAULT_PROTOCOL,
                        progress: insertion.Progress = insertion.no_progress, workers: int = 1) -> Any:
    """``studies.insertion.reproduce_insertion`` with the report's tables and figures."""
    return insertion.reproduce_insertion(root, RENDER, quick, protocol_path, progress, workers)
