"""The ex16 helper's steps (E124..), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. The probe-reach step reads only the
breadth study's stored runs and fills a group nobody else fills, so it runs in the explain target's background
process (``Explain.background``) beside the later steps.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex16_reach, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex16_reach",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex16_reach": ex16_reach.STORED}


def run(job: Any) -> None:
    """E124/E125: Table II's hinge and push1d Probe-Robust(2, 5) with probes that reach the commit regime (three
    closed-form reruns per family, in the background process)."""
    job.progress("explain: Table II's probed cells with probes that reach the commit regime (background)", 0, 1)

    def then(result: tuple[dict[str, Any], Any]) -> None:
        keys, rows = result
        job.res["ex16_reach"].update(keys)
        if len(rows):
            job.stored[ex16_reach.STORED] = rows

    job.submit(then, ex16_reach.run, Path(job.root), bool(job.quick))


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex16's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex16_reach", ex16_reach.STORED, ex16_reach.recompute)
