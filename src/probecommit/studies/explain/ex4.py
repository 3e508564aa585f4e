"""The fourth explain helper's steps (E48..), run after the others by ``Explain.run``.

Table II's single-width rule needs no step of its own: its keys are part of the prior-width
sweep's (``breadth.sweep_keys``). The prices' test reads only the paper's printed values.
"""

from __future__ import annotations

from typing import Any

from probecommit.studies.explain import ex4_pricing

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex4_pricing",)


def run(job: Any) -> None:
    """Every step, cheapest first."""
    job.progress("explain: the paper's prices from its own curve", 0, 1)
    job.res["ex4_pricing"].update(ex4_pricing.keys())
