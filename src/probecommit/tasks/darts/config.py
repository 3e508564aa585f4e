"""Config of the darts family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.darts.model import PRIOR_HIGH, PRIOR_LOW


class DartsModelConfig(ModelConfigBase):
    sigma: float = Field(0.02, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float, float] = PRIOR_LOW
    prior_high: tuple[float, float, float] = PRIOR_HIGH


class DartsSimulatorConfig(SimulatorConfigBase):
    engine: Literal["mujoco"] = "mujoco"
    noise_sigma: float = Field(0.02, ge=0, le=10)


class DartsConfig(TaskConfigBase):
    """A dart thrown with linear drag to land at a target distance."""

    family: Literal["darts"] = "darts"
    model: DartsModelConfig = DartsModelConfig()
    simulator: DartsSimulatorConfig = DartsSimulatorConfig()
    latent_names = ("k_d", "m", "g")
    context_names = ("target",)
    context_ranges = ((0.0, 100.0),)  # target (m): what the task can aim at
    positive_latents = True
    probe_dim = 2
