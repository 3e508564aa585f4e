"""Config checks of the insertion family: physical box limits and the engine settings' hooks (the
fields themselves are declared in ``probecommit.tasks.insertion``)."""

from __future__ import annotations

from typing import Any

from pydantic import model_validator

from probecommit.tasks.config import FieldError, ModelConfigBase, TaskConfigBase

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


class InsertionModelChecks(ModelConfigBase):
    """Physical limits of the model section's prior box (the base of the derived model section)."""

    @model_validator(mode="after")
    def _check(self) -> "InsertionModelChecks":
        check_box("prior_low", self.prior_low)  # type: ignore[attr-defined]
        check_box("prior_high", self.prior_high)  # type: ignore[attr-defined]
        return self


class InsertionConfigHooks(TaskConfigBase):
    """The insertion config's hooks (the base of the derived config): the engine's settings and
    the physical limits of a truth box."""

    def simulator_kwargs(self) -> dict[str, Any]:
        kwargs = {"noise_sigma": self.simulator.noise_sigma, "aim_offset": self.simulator.aim_offset}  # type: ignore[attr-defined]
        if self.simulator.engine == "analytic":  # type: ignore[attr-defined]
            kwargs.update(boundary_offset=self.simulator.boundary_offset, capture_scale=self.simulator.capture_scale)  # type: ignore[attr-defined]
        return kwargs

    def check_truth_box(self, low, high, field: str) -> None:
        super().check_truth_box(low, high, field)
        check_box(f"{field}.truth_low", low)
        check_box(f"{field}.truth_high", high)


def __getattr__(name: str):
    """The derived config classes under their former names (``InsertionConfig`` is ``SPEC.config``), for
    code written before the declaration; new code reads ``probecommit.tasks.insertion.SPEC.config``."""
    if name in ('InsertionConfig', 'InsertionModelConfig', 'InsertionSimulatorConfig'):
        from probecommit.tasks.insertion import SPEC

        config = SPEC.config
        return {"InsertionConfig": config, "InsertionModelConfig": config.model_fields["model"].annotation,
                "InsertionSimulatorConfig": config.model_fields["simulator"].annotation}[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
