"""The ex22 helper's steps (E156..), run by ``Explain.run``.

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. The exact-posterior step reads only the
breadth study's stored runs (episodes, probes, instances) and fills a group nobody else fills, so it is set aside to
a process of its own (``Explain.aside``); it runs no engine and no filter. The magnitude sweep (E158) reruns the
hinge's frozen config on its closed-form scene under five probe grids, in the same process.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex22_exact, ex22_magnitude, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex22_exact", "ex22_magnitude")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex22_exact": ex22_exact.STORED, "ex22_magnitude": ex22_magnitude.STORED}


def exact(job: Any) -> None:
    """E156/E157: Table II's push1d and hinge Probe-Robust(2, 5) decided again on the exact posterior of each stored
    episode's own readings (no resampling, no jitter), the miss from the model at the truth."""
    job.progress("explain: Table II's probed cells under the exact posterior of the stored readings", 0, 1)
    stored.fill_group(job, "ex22_exact", ex22_exact.STORED, ex22_exact.run)


def magnitude(job: Any) -> None:
    """E158: the hinge's Probe-Robust(2, 5) with its frozen release speeds scaled by each declared factor (closed-form
    reruns), against both of the paper's curve points and its k2 / k5 ratio."""
    job.progress("explain: the hinge's probe magnitudes swept", 0, 1)
    stored.fill_group(job, "ex22_magnitude", ex22_magnitude.STORED, ex22_magnitude.run)


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex22's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    values, sources, problems = stored.recompute_group(folder, results, "ex22_exact", ex22_exact.STORED,
                                                       ex22_exact.recompute)
    more = stored.recompute_group(folder, results, "ex22_magnitude", ex22_magnitude.STORED, ex22_magnitude.recompute)
    return values | more[0], sources | more[1], problems + more[2]
