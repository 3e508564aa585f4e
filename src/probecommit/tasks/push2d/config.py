"""Config of the 2-D push family (defaults are the frozen paper values, see ``__init__``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.push1d.model import PRIOR_HIGH, PRIOR_LOW
from probecommit.tasks.push2d.model import FITTED_MU_SCALE


class Push2DModelConfig(ModelConfigBase):
    sigma: float = Field(0.05, gt=0, le=10)
    margin: float = Field(1.0, gt=0, le=1.5)
    #: Effective-friction factor of the analytic model, fitted to the engine before any audit.
    mu_scale: float = Field(FITTED_MU_SCALE, gt=0.1, le=10)
    prior_low: tuple[float, float, float] = PRIOR_LOW
    prior_high: tuple[float, float, float] = PRIOR_HIGH


class Push2DSimulatorConfig(SimulatorConfigBase):
    engine: Literal["mujoco", "pybullet"] = "mujoco"
    noise_sigma: float = Field(0.05, ge=0, le=10)


class Push2DConfig(TaskConfigBase):
    """A box on a plane struck by a 2-D impulse to stop at a 2-D target."""

    family: Literal["push2d"] = "push2d"
    model: Push2DModelConfig = Push2DModelConfig()
    simulator: Push2DSimulatorConfig = Push2DSimulatorConfig()
    latent_names = ("mu", "m", "k_d")
    context_names = ("target_x", "target_y")
    context_ranges = ((-20.0, 20.0), (-20.0, 20.0))  # target (m): what the task can aim at
    positive_latents = True
    probe_dim = 1
