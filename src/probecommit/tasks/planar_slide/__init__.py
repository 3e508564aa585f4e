"""Planar slide: the example family of ``docs/adding-a-task.md`` (analytic only).

Registers ``planar_slide``: latents ``(mu, phi, m)``, a strike probe observing a 2-D
rest position, a 2-D impulse action aimed at a per-instance target, continuous miss.
"""

from __future__ import annotations

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.planar_slide.model import PRIOR_HIGH, PRIOR_LOW, PlanarSlideModel

DECLARATION = Declaration(
    name="planar_slide",
    latents=(Latent("mu", "", PRIOR_LOW[0], PRIOR_HIGH[0]),
             Latent("phi", "rad", PRIOR_LOW[1], PRIOR_HIGH[1]),
             Latent("m", "kg", PRIOR_LOW[2], PRIOR_HIGH[2])),
    probe_grid=PlanarSlideModel.probe_grid, action_grid=PlanarSlideModel.action_grid,
    loss="continuous", sigma=0.02, sigma_limit=10, decision="mu",
    contexts=(Context("target_x", "m", 0.6, 1.0, limits=(-20.0, 20.0)), Context("target_y", "m", -0.3, 0.2, limits=(-20.0, 20.0))),
    simulators={"analytic": "probecommit.tasks.planar_slide.sim_analytic:AnalyticPlanarSlideSimulator"},
    analytic=False,
    summary={"probe": "strike / 2-D rest", "action": "2-D impulse",
             "sigma": "2 cm", "budgets": "0, 2, 5", "metric": "miss (m)", "n": "example"},
    example={"instances": {"contexts": [[1.0, 0.2], [0.6, -0.3]]}, "probes": {"budget": 5, "budgets": [2, 5]}},
    doc="A puck struck at a target (example family: 3-D latent, 2-D observation and action).",
)
SPEC = family(DECLARATION, PlanarSlideModel)
