"""Config of the grasp family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.grasp.model import PRIOR_HIGH, PRIOR_LOW


class GraspModelConfig(ModelConfigBase):
    sigma: float = Field(2.0, gt=0, le=100)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float] = PRIOR_LOW
    prior_high: tuple[float, float] = PRIOR_HIGH


class GraspSimulatorConfig(SimulatorConfigBase):
    engine: Literal["mujoco", "analytic"] = "mujoco"
    noise_sigma: float = Field(2.0, ge=0, le=100)


class GraspConfig(TaskConfigBase):
    """A delicate object gripped hard enough to lift, gently enough not to crush."""

    family: Literal["grasp"] = "grasp"
    model: GraspModelConfig = GraspModelConfig()
    simulator: GraspSimulatorConfig = GraspSimulatorConfig()
    latent_names = ("mu", "m")
    positive_latents = True
    probe_dim = 1
