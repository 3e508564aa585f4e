"""The fourth explain helper's steps (E48..), run after the others by ``Explain.run``.

Table II's single-width rule needs no step of its own: its keys are part of the prior-width
sweep's (``breadth.sweep_keys``). The prices' test reads only the paper's printed values; the
grasp step reruns the model-exact grasp study at raised squeeze resolutions; the cone step
re-executes the 2-D push's stored actions under MuJoCo's default friction cone.
"""

from __future__ import annotations

from typing import Any

from probecommit.studies.explain import ex4_cone, ex4_grasp, ex4_pricing

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex4_pricing", "ex4_grasp", "ex4_cone")


def run(job: Any) -> None:
    """Every step, cheapest first."""
    job.progress("explain: the paper's prices from its own curve", 0, 1)
    job.res["ex4_pricing"].update(ex4_pricing.keys())
    job.progress("explain: grasp with the squeeze's resolution raised", 0, 1)
    factors = job.cfg["ex4_grasp_factors_quick" if job.quick else "ex4_grasp_factors"]
    keys, job.stored[ex4_grasp.STORED] = ex4_grasp.run(job.runs, factors, job.quick, job.workers)
    job.res["ex4_grasp"].update(keys)
    job.progress("explain: 2-D push under MuJoCo's default friction cone", 0, 1)
    keys, rows = ex4_cone.run(job.root, job.runs, job.boot, job.quick)
    job.res["ex4_cone"].update(keys)
    if len(rows):
        job.stored[ex4_cone.STORED] = rows
