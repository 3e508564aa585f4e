"""The ex32 helper's step (E196, E197), run by ``Explain.run``.

The step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. It reads only the breadth study's stored
runs (episodes, instances, the frozen config's model) and fills a group nobody else fills; it runs no engine, no
filter and no rerun (about a second of CPU), so it shares the process ex25's step is set aside to.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex32_floor, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex32_floor",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex32_floor": ex32_floor.STORED}


def floor(job: Any) -> None:
    """E196/E197: Table II's push1d and hinge Probe-Robust(2, 5) against the floor the action grid alone puts on the
    miss at each instance's truth (push2d's floor beside)."""
    job.progress("explain: Table II's probed cells against the action grid's floor", 0, 1)
    stored.fill_group(job, "ex32_floor", ex32_floor.STORED, ex32_floor.run)


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex32's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex32_floor", ex32_floor.STORED, ex32_floor.recompute)
