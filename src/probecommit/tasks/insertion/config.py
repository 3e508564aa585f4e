"""Config of the insertion family: model and simulator sections, validated here."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from probecommit.tasks.config import FieldError, ModelConfigBase, SimulatorConfigBase, TaskConfigBase
from probecommit.tasks.insertion.model import PAPER_DELTA_MM

#: Largest |coordinate| of a prior or truth box, and of an offset (mm): the plate is 120 mm wide.
BOX_LIMIT_MM = 50.0
#: Lowest clearance scale c with a positive capture window w(c) = 0.6 c + 1.1 (and half-gap).
MIN_CLEARANCE = -1.1 / 0.6


def check_box(field: str, box: tuple[float, ...] | None) -> None:
    """Physical limits of an insertion box ``(x_hole, c)``."""
    if box is None:
        return
    if any(abs(v) > BOX_LIMIT_MM for v in box):
        raise FieldError(field, f"coordinates must be within +-{BOX_LIMIT_MM:g} mm, got {list(box)}")
    if len(box) == 2 and box[1] <= MIN_CLEARANCE:
        raise FieldError(field, f"clearance scale c must be > {MIN_CLEARANCE:.4f} (w(c) = 0.6 c + 1.1 > 0), got {box[1]!r}")


class InsertionModelConfig(ModelConfigBase):
    """The analytic model the robot deploys."""

    boundary: Literal["deployed", "corrected"] = "deployed"
    delta: float = Field(PAPER_DELTA_MM, ge=-5, le=5)
    sigma: float = Field(0.5, gt=0, le=1000)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float] = (-10.0, 0.7)
    prior_high: tuple[float, float] = (10.0, 1.3)

    @model_validator(mode="after")
    def _check(self) -> "InsertionModelConfig":
        check_box("prior_low", self.prior_low)
        check_box("prior_high", self.prior_high)
        return self


class InsertionSimulatorConfig(SimulatorConfigBase):
    """Ground truth: the engine and simulator-side settings (separate from the model's)."""

    engine: str = "mujoco"
    noise_sigma: float = Field(0.5, ge=0, le=1000)
    aim_offset: float = Field(0.0, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)
    #: Analytic engine only: its tap boundary offset and capture scale.
    boundary_offset: float = Field(PAPER_DELTA_MM, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)
    capture_scale: float = Field(1.0, gt=0, le=100)


class InsertionConfig(TaskConfigBase):
    """Peg insertion after surface taps (paper Sec. III)."""

    family: Literal["insertion"] = "insertion"
    model: InsertionModelConfig = InsertionModelConfig()
    simulator: InsertionSimulatorConfig = InsertionSimulatorConfig()
    latent_names = ("x_hole", "c")
    probe_dim = 1

    def simulator_kwargs(self) -> dict[str, Any]:
        kwargs = {"noise_sigma": self.simulator.noise_sigma, "aim_offset": self.simulator.aim_offset}
        if self.simulator.engine == "analytic":
            kwargs.update(boundary_offset=self.simulator.boundary_offset, capture_scale=self.simulator.capture_scale)
        return kwargs

    def check_truth_box(self, low, high, field: str) -> None:
        super().check_truth_box(low, high, field)
        check_box(f"{field}.truth_low", low)
        check_box(f"{field}.truth_high", high)
