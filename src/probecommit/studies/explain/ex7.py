"""The fourth session's ex7 explain steps (E69..E72), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and reads only what ``Explain`` holds.
"""

from __future__ import annotations

from typing import Any

from probecommit.studies.explain import ex7_faults, ex7_robust

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex7_faults", "ex7_robust")


def run(job: Any) -> None:
    """The fault-harness readings (no engine runs), then the fresh MuJoCo draws of the robust filters."""
    job.progress("explain: the fault harness read over the budget and by class probability", 0, 1)
    ex7_faults.run(job)
    job.progress("explain: the mixture over fresh development and harness draws", 0, 1)
    ex7_robust.run(job)
