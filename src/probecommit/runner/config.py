"""Study configuration: YAML, validated on load, one-line errors naming the field."""

from __future__ import annotations

import math
from numbers import Real
from pathlib import Path
from typing import Any, Literal, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, StrictBool, ValidationError, field_validator, model_validator

ENGINES = ("analytic", "mujoco", "pybullet", "sapien")
METHODS = ("blind_bayes", "blind_robust", "probe_robust")


class ConfigError(ValueError):
    """A study config is invalid; the message names the field."""


#: Largest |coordinate| of a prior or truth box, and of an offset (mm): the plate is 120 mm wide.
BOX_LIMIT_MM = 50.0
#: Lowest clearance scale c with a positive capture window w(c) = 0.6 c + 1.1 (and half-gap).
MIN_CLEARANCE = -1.1 / 0.6


def _check_box(name: str, box: tuple[float, ...] | None) -> None:
    if box is not None and any(abs(v) > BOX_LIMIT_MM for v in box):
        raise _FieldError(name, f"coordinates must be within +-{BOX_LIMIT_MM:g} mm, got {list(box)}")


def _has_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return True
    return isinstance(value, (list, tuple)) and any(_has_bool(v) for v in value)


class _FieldError(ValueError):
    """A cross-field check's error, attributed to one field of its section."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"[{field}] {message}")
        self.field = field
        self.message = message


class _Strict(BaseModel):
    """Unknown keys, NaN and infinity are errors; so is a boolean where a number is due."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_numbers(cls, value: Any, info) -> Any:
        # Pydantic's lax mode reads ``true`` as 1; in a config that is a typo, not a number.
        annotation = cls.model_fields[info.field_name].annotation
        if annotation not in (bool, StrictBool) and _has_bool(value):
            raise ValueError("expected a number, got a boolean (true/false)")
        return value


class InstancesConfig(_Strict):
    """Which ground-truth instances to draw."""

    split: str = Field("demo", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    count: int = Field(16, ge=1, le=100_000)
    sampling: Literal["uniform", "lhs"] = "uniform"
    seed: int = Field(0, ge=0)
    #: Truth box, if different from the model's prior box (the prior fault draws from +-12 mm).
    truth_low: tuple[float, float] | None = None
    truth_high: tuple[float, float] | None = None

    @model_validator(mode="after")
    def _check(self) -> "InstancesConfig":
        for name in ("truth_low", "truth_high"):
            box = getattr(self, name)
            _check_box(name, box)
            if box is not None and box[1] <= MIN_CLEARANCE:
                raise _FieldError(name, f"clearance scale c must be > {MIN_CLEARANCE:.4f} (w(c) = 0.6 c + 1.1 > 0), got {box[1]!r}")
        if self.truth_low is not None and self.truth_high is not None:
            if any(h <= lo for lo, h in zip(self.truth_low, self.truth_high)):
                raise _FieldError("truth_high", f"must be > truth_low in every coordinate, got {list(self.truth_high)} vs {list(self.truth_low)}")
        return self


class ProbesConfig(_Strict):
    """Probe schedule: ``random`` (i.i.d. uniform with replacement) or a fixed list."""

    schedule: Union[Literal["random"], list[float]] = "random"
    budget: int = Field(8, ge=1, le=64)
    budgets: list[int] | None = Field(None, min_length=1)

    @field_validator("schedule", mode="before")
    @classmethod
    def _schedule(cls, value: Any) -> Any:
        # One clear message instead of pydantic's two union-branch errors.
        if value == "random" and isinstance(value, str):
            return value
        if isinstance(value, (list, tuple)):
            for i, v in enumerate(value):
                if isinstance(v, bool) or not isinstance(v, Real) or not math.isfinite(v):
                    raise ValueError(f"probe {i} of the schedule must be a finite number (mm), got {v!r}")
            return [float(v) for v in value]
        raise ValueError(f"must be 'random' or a list of probe positions (mm), got {value!r}")

    @model_validator(mode="after")
    def _check(self) -> "ProbesConfig":
        if isinstance(self.schedule, list) and len(self.schedule) < self.budget:
            raise _FieldError("schedule", f"has {len(self.schedule)} probes but budget is {self.budget}")
        if self.budgets is not None:
            bad = [k for k in self.budgets if not 1 <= k <= self.budget]
            if bad:
                raise _FieldError("budgets", f"{bad} out of range 1..{self.budget} (the budget)")
        return self

    @property
    def commit_budgets(self) -> list[int]:
        return sorted(set(self.budgets)) if self.budgets else list(range(1, self.budget + 1))


class ModelConfig(_Strict):
    """The analytic model the robot deploys."""

    boundary: Literal["deployed", "corrected"] = "deployed"
    delta: float = Field(0.905, ge=-5, le=5)
    sigma: float = Field(0.5, gt=0, le=1000)
    margin: float = Field(1.0, gt=0, le=1.5)
    prior_low: tuple[float, float] = (-10.0, 0.7)
    prior_high: tuple[float, float] = (10.0, 1.3)

    @model_validator(mode="after")
    def _check(self) -> "ModelConfig":
        _check_box("prior_low", self.prior_low)
        _check_box("prior_high", self.prior_high)
        if self.prior_low[1] <= MIN_CLEARANCE:
            raise _FieldError("prior_low", f"clearance scale c must be > {MIN_CLEARANCE:.4f} (w(c) = 0.6 c + 1.1 > 0), got {self.prior_low[1]!r}")
        if any(h <= lo for lo, h in zip(self.prior_low, self.prior_high)):
            raise _FieldError("prior_high", f"must be > prior_low in every coordinate, got {list(self.prior_high)} vs {list(self.prior_low)}")
        return self


class BeliefConfig(_Strict):
    """Particle filter settings."""

    particles: int = Field(1024, ge=1, le=1_000_000)
    nu: float = Field(0.8, gt=0, le=1)
    resample_fraction: float = Field(0.5, gt=0, le=1)
    jitter: StrictBool = True
    likelihood: Literal["gaussian", "tempered", "mixture"] = "gaussian"
    temperature: float = Field(1.0, ge=1, le=1e6)
    epsilon: float = Field(0.0, ge=0, lt=1)
    mixture_low: float = Field(-17.0, ge=-1000, le=1000)
    mixture_high: float = Field(2.0, ge=-1000, le=1000)
    rejuvenation: float = Field(0.0, ge=0, lt=1)

    @model_validator(mode="after")
    def _check(self) -> "BeliefConfig":
        if self.mixture_high <= self.mixture_low:
            raise _FieldError("mixture_high", f"must be > mixture_low, got {self.mixture_high!r} <= {self.mixture_low!r}")
        return self


class SimulatorConfig(_Strict):
    """Ground truth: the engine and simulator-side settings (separate from the model's)."""

    engine: str = "mujoco"
    noise_sigma: float = Field(0.5, ge=0, le=1000)
    aim_offset: float = Field(0.0, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)
    #: Analytic engine only: its tap boundary offset and capture scale.
    boundary_offset: float = Field(0.905, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)
    capture_scale: float = Field(1.0, gt=0, le=100)
    #: Execute every aim of the grid once per instance, so replays and calibration
    #: under any model never need the engine again.
    execute_all_aims: StrictBool = True

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
    methods: list[Literal["blind_bayes", "blind_robust", "probe_robust"]] = Field(list(METHODS), min_length=1)
    blind_prior_samples: int = Field(20_000, ge=100, le=10_000_000)
    #: Instances per work unit; a unit is the resumable, parallel grain.
    unit_instances: int = Field(4, ge=1, le=1000)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        # The name is the default run directory under runs/: '.' or '..' would escape it.
        if set(value) == {"."}:
            raise ValueError(f"must contain a letter, digit, '_' or '-', got {value!r}")
        return value

    @field_validator("methods")
    @classmethod
    def _unique_methods(cls, value: list[str]) -> list[str]:
        dup = sorted({m for m in value if value.count(m) > 1})
        if dup:
            raise ValueError(f"lists {', '.join(dup)} more than once")
        return value

    @model_validator(mode="after")
    def _check(self) -> "StudyConfig":
        inst, model = self.instances, self.model
        low = inst.truth_low if inst.truth_low is not None else model.prior_low
        high = inst.truth_high if inst.truth_high is not None else model.prior_high
        if any(h <= lo for lo, h in zip(low, high)):
            which = "truth_high" if inst.truth_high is not None else "truth_low"
            raise _FieldError(
                f"instances.{which}",
                f"truth box must have high > low in every coordinate, got low {list(low)}, high {list(high)} "
                "(an unset end defaults to the model's prior box)",
            )
        return self


def _one_line(text: str) -> str:
    return " ".join(text.replace("\r", " ").replace("\n", " ").split())


def _loc_part(part: Any) -> str:
    text = str(part)
    # Keys come from the user's file: escape anything that would break the line.
    return text if text.isprintable() else text.encode("unicode_escape").decode("ascii")


def _format_error(exc: ValidationError) -> str:
    first = exc.errors()[0]
    loc = [_loc_part(p) for p in first["loc"]]
    msg = first["msg"].removeprefix("Value error, ")
    cause = first.get("ctx", {}).get("error")
    if isinstance(cause, _FieldError):
        loc, msg = loc + [cause.field], cause.message
        loc = [p for part in loc for p in part.split(".")]
    field = ".".join(loc) or "config"
    extra = f" (and {exc.error_count() - 1} more)" if exc.error_count() > 1 else ""
    return _one_line(f"invalid config field '{field}': {msg}{extra}")


def parse_config(data: dict) -> StudyConfig:
    """Validate a config mapping.

    Raises:
        ConfigError: One line, ``invalid config field '<dotted.name>': <why>``,
            naming the first bad field (and how many more there are).
    """
    if not isinstance(data, dict):
        raise ConfigError(f"config must be a mapping of fields, got {type(data).__name__}")
    try:
        return StudyConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_format_error(exc)) from None
    except (ValueError, TypeError, RecursionError) as exc:  # pragma: no cover - defensive
        raise ConfigError(_one_line(f"invalid config: {type(exc).__name__}: {exc}")) from None


class _UniqueKeyLoader(yaml.SafeLoader):
    """Safe YAML loader that refuses a key given twice (YAML would keep the last silently)."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    loader.flatten_mapping(node)
    seen: dict[Any, Any] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            duplicate = key in seen
        except TypeError:  # unhashable key: let the base constructor report it
            break
        if duplicate:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (first at line {seen[key].start_mark.line + 1})", key_node.start_mark
            )
        seen[key] = key_node
    return loader.construct_mapping(node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _yaml_error(path: Path, exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    problem = getattr(exc, "problem", None) or getattr(exc, "context", None) or str(exc).splitlines()[0]
    return _one_line(f"{path}: not valid YAML{where}: {problem}")


def load_config(path: str | Path) -> StudyConfig:
    """Load and validate a YAML study config.

    An empty file is the default config; anything else must be a mapping.

    Raises:
        ConfigError: One line naming the file (unreadable, not YAML, duplicate key)
            or, from :func:`parse_config`, the bad field.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text (byte {exc.start}); a config is a YAML text file") from None
    except OSError as exc:
        raise ConfigError(_one_line(f"{path}: cannot read: {exc.strerror or exc}")) from None
    try:
        data = yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise ConfigError(_yaml_error(path, exc)) from None
    except (ValueError, TypeError, RecursionError) as exc:  # e.g. unhashable keys, absurd nesting
        raise ConfigError(_one_line(f"{path}: not a usable YAML mapping: {type(exc).__name__}: {exc}")) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config must be a mapping of fields, got a YAML {type(data).__name__}")
    try:
        return parse_config(data)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def dump_config(config: StudyConfig) -> str:
    return yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False)
