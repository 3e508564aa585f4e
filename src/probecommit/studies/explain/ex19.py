"""The ex19 helper's steps (E138..), run by ``Explain.run`` after the prior-width sweep (``more``).

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. The darts step reads the runs of the
prior-width sweep (E38) and its published keys, so it runs in place once that sweep is done; it runs no engine.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex19_darts, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex19_darts",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex19_darts": ex19_darts.STORED}


def run(job: Any) -> None:
    """E138: darts' row at E38's widths with its truth set redrawn (the model on stored blind actions)."""
    job.progress("explain: darts' row at the prior's widths with its truths redrawn", 0, 1)
    keys, rows = ex19_darts.run(job.root, job.runs, job.cfg, job.res["breadth_prior"], job.quick)
    job.res["ex19_darts"].update(keys)
    if len(rows):
        job.stored[ex19_darts.STORED] = rows


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex19's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex19_darts", ex19_darts.STORED, ex19_darts.recompute)
