"""Planar slide: the example family of ``docs/adding-a-task.md`` (analytic only).

Registers ``planar_slide``: latents ``(mu, phi, m)``, a strike probe observing a 2-D
rest position, a 2-D impulse action aimed at a per-instance target, continuous miss.
"""

from __future__ import annotations

from probecommit.tasks.base import TaskSpec
from probecommit.tasks.planar_slide.config import PlanarSlideConfig
from probecommit.tasks.planar_slide.model import PlanarSlideModel
from probecommit.tasks.registry import register


def build_model(config: PlanarSlideConfig) -> PlanarSlideModel:
    return PlanarSlideModel(**config.model.model_kwargs())


SPEC = register(
    TaskSpec(
        name="planar_slide",
        config=PlanarSlideConfig,
        build_model=build_model,
        simulators={"analytic": "probecommit.tasks.planar_slide.sim_analytic:AnalyticPlanarSlideSimulator"},
        summary={"latents": "mu, phi, m", "probe": "strike / 2-D rest", "action": "2-D impulse",
                 "sigma": "2 cm", "budgets": "0, 2, 5", "metric": "miss (m)", "n": "example"},
        example={"instances": {"contexts": [[1.0, 0.2], [0.6, -0.3]]}, "probes": {"budget": 5, "budgets": [2, 5]}},
    )
)
