"""Config of the hinge family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.hinge.model import PRIOR_HIGH, PRIOR_LOW


class HingeModelConfig(ModelConfigBase):
    sigma: float = Field(0.02, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float, float] = PRIOR_LOW
    prior_high: tuple[float, float, float] = PRIOR_HIGH


class HingeSimulatorConfig(SimulatorConfigBase):
    engine: Literal["mujoco", "analytic"] = "mujoco"
    noise_sigma: float = Field(0.02, ge=0, le=10)


class HingeConfig(TaskConfigBase):
    """A door on a hinge released to coast to a target angle."""

    family: Literal["hinge"] = "hinge"
    model: HingeModelConfig = HingeModelConfig()
    simulator: HingeSimulatorConfig = HingeSimulatorConfig()
    latent_names = ("f", "b", "m")
    context_names = ("target",)
    context_ranges = ((0.0, 6.2832),)  # target (rad): what the task can aim at
    positive_latents = True
    probe_dim = 1
