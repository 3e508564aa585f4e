"""Config of the shuffleboard family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.shuffleboard.model import PRIOR_HIGH, PRIOR_LOW


class ShuffleboardModelConfig(ModelConfigBase):
    sigma: float = Field(0.05, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float, float] = PRIOR_LOW
    prior_high: tuple[float, float, float] = PRIOR_HIGH


class ShuffleboardSimulatorConfig(SimulatorConfigBase):
    engine: Literal["sapien", "analytic"] = "sapien"
    noise_sigma: float = Field(0.05, ge=0, le=10)


class ShuffleboardConfig(TaskConfigBase):
    """A puck struck along a board to stop at a target distance."""

    family: Literal["shuffleboard"] = "shuffleboard"
    model: ShuffleboardModelConfig = ShuffleboardModelConfig()
    simulator: ShuffleboardSimulatorConfig = ShuffleboardSimulatorConfig()
    latent_names = ("mu", "m", "k_d")
    context_names = ("target",)
    context_ranges = ((0.0, 50.0),)  # target (m): what the task can aim at
    positive_latents = True
    probe_dim = 1
