"""Config of the 1-D push family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.push1d.model import PRIOR_HIGH, PRIOR_LOW


class Push1DModelConfig(ModelConfigBase):
    sigma: float = Field(0.05, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float, float] = PRIOR_LOW
    prior_high: tuple[float, float, float] = PRIOR_HIGH


class Push1DSimulatorConfig(SimulatorConfigBase):
    engine: Literal["analytic"] = "analytic"
    noise_sigma: float = Field(0.05, ge=0, le=10)


class Push1DConfig(TaskConfigBase):
    """A box pushed along a line by an impulse to stop at a target distance."""

    family: Literal["push1d"] = "push1d"
    model: Push1DModelConfig = Push1DModelConfig()
    simulator: Push1DSimulatorConfig = Push1DSimulatorConfig()
    latent_names = ("mu", "m", "k_d")
    context_names = ("target",)
    context_ranges = ((0.0, 20.0),)  # target (m): what the task can aim at
    positive_latents = True
    probe_dim = 1
