"""Config of the planar-slide family."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase


class PlanarSlideModelConfig(ModelConfigBase):
    sigma: float = Field(0.02, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float, float] = (0.2, -0.2, 0.5)
    prior_high: tuple[float, float, float] = (0.6, 0.2, 1.5)


class PlanarSlideSimulatorConfig(SimulatorConfigBase):
    engine: Literal["analytic"] = "analytic"
    noise_sigma: float = Field(0.02, ge=0, le=10)


class PlanarSlideConfig(TaskConfigBase):
    """A puck struck at a target (example family: 3-D latent, 2-D observation and action)."""

    family: Literal["planar_slide"] = "planar_slide"
    model: PlanarSlideModelConfig = PlanarSlideModelConfig()
    simulator: PlanarSlideSimulatorConfig = PlanarSlideSimulatorConfig()
    latent_names = ("mu", "phi", "m")
    context_names = ("target_x", "target_y")
    context_ranges = ((-20.0, 20.0), (-20.0, 20.0))  # target (m): what the task can aim at
    probe_dim = 1
