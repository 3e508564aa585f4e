"""The ex25 helper's steps (E174..), run by ``Explain.run``.

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. The interval-probe step reads only the
breadth study's stored runs and the frozen configs, runs closed-form scenes (no MuJoCo) and fills a group nobody else
fills, so it is set aside to a process of its own (``Explain.aside``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex25_uniform, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex25_uniform",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex25_uniform": ex25_uniform.STORED}


def uniform(job: Any) -> None:
    """E174/E175: Table II's push1d and hinge Probe-Robust(2, 5) with probes uniform over the frozen grid's span
    (closed-form reruns), against both of the paper's curve points and its k2 / k5 ratio."""
    job.progress("explain: Table II's probed cells with probes uniform over the probe interval", 0, 1)
    stored.fill_group(job, "ex25_uniform", ex25_uniform.STORED, ex25_uniform.run)


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex25's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    return stored.recompute_group(folder, results, "ex25_uniform", ex25_uniform.STORED, ex25_uniform.recompute)
