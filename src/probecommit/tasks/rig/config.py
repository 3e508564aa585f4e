"""Config checks of the rig family: physical box limits and the simulated rig's hooks (the fields
themselves are declared in ``probecommit.tasks.rig``)."""

from __future__ import annotations

from typing import Any

from pydantic import model_validator

from probecommit.tasks.config import FieldError, ModelConfigBase, TaskConfigBase
from probecommit.tasks.rig.model import RIG_SCALE

#: Largest |x_hole| of a prior or truth box (mm): the block is 4 x 120 mm wide at rig scale.
RIG_BOX_LIMIT_MM = 50.0 * RIG_SCALE


def check_rig_box(field: str, box: tuple[float, ...] | None) -> None:
    if box is None:
        return
    if abs(box[0]) > RIG_BOX_LIMIT_MM:
        raise FieldError(field, f"x_hole must be within +-{RIG_BOX_LIMIT_MM:g} mm, got {box[0]!r}")
    if len(box) == 2 and box[1] <= -1.1 / 0.6:
        raise FieldError(field, f"clearance scale c must be > {-1.1 / 0.6:.4f} (a positive window), got {box[1]!r}")


class RigModelChecks(ModelConfigBase):
    """Physical limits of the model section's prior box (the base of the derived model section)."""

    @model_validator(mode="after")
    def _check(self) -> "RigModelChecks":
        check_rig_box("prior_low", self.prior_low)  # type: ignore[attr-defined]
        check_rig_box("prior_high", self.prior_high)  # type: ignore[attr-defined]
        return self


class RigConfigHooks(TaskConfigBase):
    """The rig config's hooks (the base of the derived config): the simulated rig's settings and
    the physical limits of a truth box."""

    def simulator_kwargs(self) -> dict[str, Any]:
        sim = self.simulator  # type: ignore[attr-defined]
        return {"noise_sigma": sim.noise_sigma, "misread_rate": sim.misread_rate, "aim_offset": sim.aim_offset}

    def check_truth_box(self, low, high, field: str) -> None:
        super().check_truth_box(low, high, field)
        check_rig_box(f"{field}.truth_low", low)
        check_rig_box(f"{field}.truth_high", high)


__all__ = ["RIG_BOX_LIMIT_MM", "RigConfigHooks", "RigModelChecks", "check_rig_box"]


def __getattr__(name: str):
    """The derived config classes under their former names (``RigConfig`` is ``SPEC.config``), for
    code written before the declaration; new code reads ``probecommit.tasks.rig.SPEC.config``."""
    if name in ('RigConfig', 'RigModelConfig', 'RigSimulatorConfig'):
        from probecommit.tasks.rig import SPEC

        config = SPEC.config
        return {"RigConfig": config, "RigModelConfig": config.model_fields["model"].annotation,
                "RigSimulatorConfig": config.model_fields["simulator"].annotation}[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
