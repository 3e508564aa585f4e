"""Study configuration: YAML, validated on load, one-line errors naming the field."""

from __future__ import annotations

from pathlib import Path
from typing import Literal, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

ENGINES = ("analytic", "mujoco", "pybullet", "sapien")
METHODS = ("blind_bayes", "blind_robust", "probe_robust")


class ConfigError(ValueError):
    """A study config is invalid; the message names the field."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class InstancesConfig(_Strict):
    """Which ground-truth instances to draw."""

    split: str = Field("demo", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    count: int = Field(16, ge=1, le=100_000)
    sampling: Literal["uniform", "lhs"] = "uniform"
    seed: int = Field(0, ge=0)
    #: Truth box, if different from the model's prior box (the prior fault draws from +-12 mm).
    truth_low: tuple[float, float] | None = None
    truth_high: tuple[float, float] | None = None


class ProbesConfig(_Strict):
    """Probe schedule: ``random`` (i.i.d. uniform with replacement) or a fixed list."""

    schedule: Union[Literal["random"], list[float]] = "random"
    budget: int = Field(8, ge=1, le=64)
    budgets: list[int] | None = None

    @model_validator(mode="after")
    def _check(self) -> "ProbesConfig":
        if isinstance(self.schedule, list) and len(self.schedule) < self.budget:
            raise ValueError(f"schedule has {len(self.schedule)} probes but budget is {self.budget}")
        if self.budgets is not None:
            bad = [k for k in self.budgets if not 1 <= k <= self.budget]
            if bad:
                raise ValueError(f"budgets {bad} out of range 1..{self.budget}")
        return self

    @property
    def commit_budgets(self) -> list[int]:
        return sorted(set(self.budgets)) if self.budgets else list(range(1, self.budget + 1))


class ModelConfig(_Strict):
    """The analytic model the robot deploys."""

    boundary: Literal["deployed", "corrected"] = "deployed"
    delta: float = Field(0.905, ge=-5, le=5)
    sigma: float = Field(0.5, gt=0)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float] = (-10.0, 0.7)
    prior_high: tuple[float, float] = (10.0, 1.3)


class BeliefConfig(_Strict):
    """Particle filter settings."""

    particles: int = Field(1024, ge=1, le=1_000_000)
    nu: float = Field(0.8, gt=0, le=1)
    resample_fraction: float = Field(0.5, gt=0, le=1)
    jitter: bool = True
    likelihood: Literal["gaussian", "tempered", "mixture"] = "gaussian"
    temperature: float = Field(1.0, ge=1)
    epsilon: float = Field(0.0, ge=0, lt=1)
    mixture_low: float = -17.0
    mixture_high: float = 2.0
    rejuvenation: float = Field(0.0, ge=0, lt=1)


class SimulatorConfig(_Strict):
    """Ground truth: the engine and simulator-side settings (separate from the model's)."""

    engine: str = "mujoco"
    noise_sigma: float = Field(0.5, ge=0)
    aim_offset: float = 0.0
    #: Analytic engine only: its tap boundary offset and capture scale.
    boundary_offset: float = 0.905
    capture_scale: float = Field(1.0, gt=0)
    #: Execute every aim of the grid once per instance, so replays and calibration
    #: under any model never need the engine again.
    execute_all_aims: bool = True

    @field_validator("engine")
    @classmethod
    def _engine(cls, v: str) -> str:
        if v not in ENGINES:
            raise ValueError(f"unknown engine {v!r}; choose one of {', '.join(ENGINES)}")
        return v


class StudyConfig(_Strict):
    """One study: instances x repeats x probe schedule x budgets, one model, one engine."""

    name: str = Field("study", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    task: Literal["insertion"] = "insertion"
    seed: int = Field(0, ge=0)
    repeats: int = Field(4, ge=1, le=1000)
    instances: InstancesConfig = InstancesConfig()
    probes: ProbesConfig = ProbesConfig()
    model: ModelConfig = ModelConfig()
    belief: BeliefConfig = BeliefConfig()
    simulator: SimulatorConfig = SimulatorConfig()
    methods: list[Literal["blind_bayes", "blind_robust", "probe_robust"]] = list(METHODS)
    blind_prior_samples: int = Field(20_000, ge=100)
    #: Instances per work unit; a unit is the resumable, parallel grain.
    unit_instances: int = Field(4, ge=1, le=1000)


def _format_error(exc: ValidationError) -> str:
    first = exc.errors()[0]
    field = ".".join(str(p) for p in first["loc"]) or "config"
    msg = first["msg"].removeprefix("Value error, ")
    extra = f" (and {exc.error_count() - 1} more)" if exc.error_count() > 1 else ""
    return f"invalid config field '{field}': {msg}{extra}"


def parse_config(data: dict) -> StudyConfig:
    """Validate a config mapping; raises ConfigError naming the first bad field."""
    if not isinstance(data, dict):
        raise ConfigError(f"config must be a mapping of fields, got {type(data).__name__}")
    try:
        return StudyConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_format_error(exc)) from None


def load_config(path: str | Path) -> StudyConfig:
    """Load and validate a YAML study config."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {str(exc).splitlines()[0]}") from None
    return parse_config(data or {})


def dump_config(config: StudyConfig) -> str:
    return yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False)
