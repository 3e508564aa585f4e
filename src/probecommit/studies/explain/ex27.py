"""The ex27 helper's step (E182..E184), run by ``Explain.run``.

The step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. It reads only the breadth study's stored
hinge run and the frozen config, reruns the hinge on MuJoCo with its commit a torque (three declared durations) and
fills a group nobody else fills, so it is set aside to a process of its own (``Explain.aside``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex27_torque, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex27_torque",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex27_torque": ex27_torque.STORED}


def torque(job: Any) -> None:
    """E182..E184: Table II's hinge row with the commit a torque (impulse, 0.25 s, 1 s) on MuJoCo, against the
    paper's Blind-Bayes, both Probe-Robust curve points and its k2 / k5 ratio."""
    job.progress("explain: Table II's hinge row with the commit a torque", 0, 1)
    stored.fill_group(job, "ex27_torque", ex27_torque.STORED, ex27_torque.run)


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex27's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex27_torque", ex27_torque.STORED, ex27_torque.recompute)
