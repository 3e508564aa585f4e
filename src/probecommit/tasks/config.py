"""Config building blocks every family's config uses (pydantic, strict).

A family's config is one branch of the study config's discriminated union: a
:class:`TaskConfigBase` subclass with ``family: Literal["<name>"]`` and its own
``model`` and ``simulator`` sections, so each family owns and validates its fields.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictBool, field_validator, model_validator
from probecommit.errors import UserError


class ConfigError(UserError, ValueError):
    """A study config is invalid; the message names the field."""


class FieldError(ValueError):
    """A cross-field check's error, attributed to one field of its section."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"[{field}] {message}")
        self.field = field
        self.message = message


def has_bool(value: Any, _depth: int = 0) -> bool:
    """Whether a (nested list of) value(s) holds a boolean; depth-bounded."""
    if isinstance(value, bool):
        return True
    if _depth > 4 or not isinstance(value, (list, tuple)):
        return False
    return any(has_bool(v, _depth + 1) for v in value[:10_000])


class StrictModel(BaseModel):
    """Unknown keys, NaN and infinity are errors; so is a boolean where a number is due."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_numbers(cls, value: Any, info) -> Any:
        # Pydantic's lax mode reads ``true`` as 1; in a config that is a typo, not a number.
        annotation = cls.model_fields[info.field_name].annotation
        if annotation not in (bool, StrictBool) and has_bool(value):
            raise ValueError("expected a number, got a boolean (true/false)")
        if annotation is int and isinstance(value, (str, float)) and not isinstance(value, bool):
            # YAML reads "1e3" as a string (YAML 1.1 wants "1.0e3"); an integral number is an integer.
            try:
                number = float(value)
            except ValueError:
                return value
            if number.is_integer() and abs(number) < 2**53:
                return int(number)
            raise ValueError(f"must be an integer, got {value!r}")
        return value


class ModelConfigBase(StrictModel):
    """Fields every family's model section has: the likelihood's sigma and the prior box."""

    sigma: float = Field(gt=0, le=1e6)
    prior_low: tuple[float, ...]
    prior_high: tuple[float, ...]

    def model_kwargs(self) -> dict[str, Any]:
        """The section as keyword arguments of the family's model: every field, the prior box as arrays."""
        kwargs = self.model_dump()
        kwargs["prior_low"] = np.array(self.prior_low, dtype=float)
        kwargs["prior_high"] = np.array(self.prior_high, dtype=float)
        return kwargs

    @model_validator(mode="after")
    def _check_prior(self) -> "ModelConfigBase":
        if len(self.prior_low) != len(self.prior_high):
            raise FieldError("prior_high", f"has {len(self.prior_high)} coordinates but prior_low has {len(self.prior_low)}")
        if any(h <= lo for lo, h in zip(self.prior_low, self.prior_high)):
            raise FieldError("prior_high", f"must be > prior_low in every coordinate, got {list(self.prior_high)} vs {list(self.prior_low)}")
        return self


class SimulatorConfigBase(StrictModel):
    """Fields every family's simulator section has."""

    engine: str = "analytic"
    noise_sigma: float = Field(ge=0, le=1e6)
    #: Execute every action of the grid once per instance up front, so replays and calibration
    #: under any model never need the engine again. Off: an action is executed when an episode
    #: commits to it (a paper split commits to 8-17 of insertion's 41 aims per instance).
    execute_all_aims: StrictBool = False


class TaskConfigBase(BaseModel):
    """One family's config: ``family`` (the union's tag), ``model`` and ``simulator``.

    Subclasses set ``latent_names`` and ``probe_dim`` (class constants used to check
    truth boxes and probe schedules before anything runs) and may override the hooks.
    """

    # Not StrictModel: its wildcard before-validator may not touch the union's tag;
    # the sections below are strict.
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    family: str
    latent_names: ClassVar[tuple[str, ...]] = ()
    context_names: ClassVar[tuple[str, ...]] = ()
    probe_dim: ClassVar[int] = 1
    #: Every latent is a physical magnitude that must be > 0 (friction, mass, damping, ...).
    positive_latents: ClassVar[bool] = False
    #: Per latent, whether it must be > 0 (a declared family's; empty: ``positive_latents`` for all).
    latent_positive: ClassVar[tuple[bool, ...]] = ()

    @classmethod
    def positive_mask(cls) -> tuple[bool, ...]:
        """Per latent, whether it is declared positive."""
        return tuple(cls.latent_positive) or (cls.positive_latents,) * len(cls.latent_names)
    #: Open range ``(low, high)`` of each context coordinate (a target the task can aim at).
    context_ranges: ClassVar[tuple[tuple[float, float], ...]] = ()

    @model_validator(mode="after")
    def _check_engine(self) -> "TaskConfigBase":
        from probecommit.tasks.registry import get

        engines = get(self.family).engines
        engine = self.simulator.engine  # type: ignore[attr-defined]
        if engine not in engines:
            raise FieldError("simulator.engine", f"task family {self.family!r} has no {engine!r} simulator; it has: {', '.join(engines)}")
        n = len(self.latent_names)
        if n and len(self.model.prior_low) != n:  # type: ignore[attr-defined]
            raise FieldError("model.prior_low", f"needs {n} coordinates ({', '.join(self.latent_names)}), got {len(self.model.prior_low)}")  # type: ignore[attr-defined]
        return self

    def simulator_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of the family's simulator classes (default: the simulator section less ``engine``)."""
        return self.simulator.model_dump(exclude={"engine", "execute_all_aims"})  # type: ignore[attr-defined]

    def check_contexts(self, rows: list[tuple[float, ...]], field: str) -> None:
        """Every context row within the family's ``context_ranges`` (the same limits, however given).

        Raises:
            FieldError: naming ``field``, the row and the coordinate.
        """
        for i, row in enumerate(rows):
            for name, value, (low, high) in zip(self.context_names, row, self.context_ranges):
                if not low < value < high:
                    raise FieldError(field, f"row {i}: {name} = {value!r} is outside ({low:g}, {high:g}), the range "
                                     f"of a {self.family} target")

    def check_truth_box(self, low: tuple[float, ...], high: tuple[float, ...], field: str) -> None:
        """Family checks on a truth box beyond its shape (override to add physical limits).

        Raises:
            FieldError: naming ``field``.
        """
        n = len(self.latent_names)
        for name, box in (("truth_low", low), ("truth_high", high)):
            if n and len(box) != n:
                raise FieldError(f"{field}.{name}", f"needs {n} coordinates ({', '.join(self.latent_names)}), got {len(box)}")
        if any(not np.isfinite(v) or abs(v) > 1e9 for v in (*low, *high)):
            raise FieldError(f"{field}.truth_high", f"values must be finite and below 1e9 in magnitude, got "
                             f"{list(low)} .. {list(high)}")
        mask = self.positive_mask()
        bad = [name for name, positive, v in zip(self.latent_names, mask, low) if positive and v <= 0]
        if bad:
            listed = bad[0] if len(bad) == 1 else f"{', '.join(bad[:-1])} and {bad[-1]}"
            raise FieldError(f"{field}.truth_low", f"{listed} must be positive, got {list(low)}")
