"""Config of the rig family: the insertion config at rig scale, validated here."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from probecommit.tasks.config import FieldError, ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.rig.model import DESCENT_STEP_MM, RIG_SCALE, TOOL_RADIUS_MM

#: Largest |x_hole| of a prior or truth box (mm): the block is 4 x 120 mm wide at rig scale.
RIG_BOX_LIMIT_MM = 50.0 * RIG_SCALE


def check_rig_box(field: str, box: tuple[float, ...] | None) -> None:
    if box is None:
        return
    if abs(box[0]) > RIG_BOX_LIMIT_MM:
        raise FieldError(field, f"x_hole must be within +-{RIG_BOX_LIMIT_MM:g} mm, got {box[0]!r}")
    if len(box) == 2 and box[1] <= -1.1 / 0.6:
        raise FieldError(field, f"clearance scale c must be > {-1.1 / 0.6:.4f} (a positive window), got {box[1]!r}")


class RigModelConfig(ModelConfigBase):
    """The rig model the robot deploys.

    ``boundary_pull_in`` is the injected boundary fault: the through-the-opening
    boundary moved inward by that many mm (0 = as deployed).
    """

    sigma: float = Field(DESCENT_STEP_MM, gt=0, le=1000)
    margin: float = Field(1.0, gt=0, le=1.5)
    boundary_pull_in: float = Field(0.0, ge=-20, le=40)
    prior_low: tuple[float, float] = (-10.0 * RIG_SCALE, 0.7)
    prior_high: tuple[float, float] = (10.0 * RIG_SCALE, 1.3)

    @model_validator(mode="after")
    def _check(self) -> "RigModelConfig":
        check_rig_box("prior_low", self.prior_low)
        check_rig_box("prior_high", self.prior_high)
        return self


class RigSimulatorConfig(SimulatorConfigBase):
    """The simulated rig: MuJoCo (touch-switch descent) or the analytic rig.

    ``misread_rate`` is the probability that the switch reports the other outcome
    (a bounce on the edge, a late close); ``aim_offset`` is the frame fault.
    """

    engine: str = "mujoco"
    noise_sigma: float = Field(0.0, ge=0, le=1000)
    misread_rate: float = Field(0.01, ge=0, lt=1)
    aim_offset: float = Field(0.0, ge=-RIG_BOX_LIMIT_MM, le=RIG_BOX_LIMIT_MM)


class RigConfig(TaskConfigBase):
    """Tool insertion into a machined pocket by touch, at rig scale (paper Sec. V-D)."""

    family: Literal["rig"] = "rig"
    model: RigModelConfig = RigModelConfig()
    simulator: RigSimulatorConfig = RigSimulatorConfig()
    latent_names = ("x_hole", "c")
    probe_dim = 1

    def simulator_kwargs(self) -> dict[str, Any]:
        sim = self.simulator
        return {"noise_sigma": sim.noise_sigma, "misread_rate": sim.misread_rate, "aim_offset": sim.aim_offset}

    def check_truth_box(self, low, high, field: str) -> None:
        super().check_truth_box(low, high, field)
        check_rig_box(f"{field}.truth_low", low)
        check_rig_box(f"{field}.truth_high", high)


__all__ = ["RigConfig", "RigModelConfig", "RigSimulatorConfig", "TOOL_RADIUS_MM"]
