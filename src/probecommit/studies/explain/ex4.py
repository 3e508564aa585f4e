"""The fourth explain helper's steps (E48..), run after the others by ``Explain.run``.

Table II's single-width rule needs no step of its own: its keys are part of the prior-width
sweep's (``breadth.sweep_keys``). The prices' test reads only the paper's printed values; the
grasp step reruns the model-exact grasp study at raised squeeze resolutions.
"""

from __future__ import annotations

from typing import Any

from probecommit.studies.explain import ex4_grasp, ex4_pricing

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex4_pricing", "ex4_grasp")


def run(job: Any) -> None:
    """Every step, cheapest first."""
    job.progress("explain: the paper's prices from its own curve", 0, 1)
    job.res["ex4_pricing"].update(ex4_pricing.keys())
    job.progress("explain: grasp with the squeeze's resolution raised", 0, 1)
    factors = job.cfg["ex4_grasp_factors_quick" if job.quick else "ex4_grasp_factors"]
    job.res["ex4_grasp"].update(ex4_grasp.run(job.runs, factors, job.quick, job.workers))
