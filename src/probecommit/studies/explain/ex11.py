"""The ex11 helper's steps (E94..), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex11_probe, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex11_probe",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex11_probe": ex11_probe.STORED}


def run(job: Any) -> None:
    """E94/E95: Table II's hinge and 2-D push Probe-Robust(5) cells over truth sets redrawn from one pool of truths
    per family (run once here: Probe-Robust at k = 5 only)."""
    job.progress("explain: Table II's Probe-Robust cells over redrawn truth sets", 0, 1)
    draws = int(job.cfg["ex11_probe_draws_quick" if job.quick else "ex11_probe_draws"])
    keys, rows = ex11_probe.run(job.root, job.runs, draws, job.quick, job.workers)
    job.res["ex11_probe"].update(keys)
    if len(rows):
        job.stored[ex11_probe.STORED] = rows


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex11's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex11_probe", ex11_probe.STORED, ex11_probe.recompute)
