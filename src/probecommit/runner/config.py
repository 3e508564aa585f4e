"""Study configuration: YAML, validated on load, one-line errors naming the field."""

from __future__ import annotations

import math
from numbers import Real
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import yaml

from probecommit.store.yamlsafe import YamlError, load_yaml
from pydantic import Field, StrictBool, ValidationError, field_validator, model_validator

from probecommit.tasks.config import ConfigError, FieldError as _FieldError, StrictModel as _Strict
from probecommit.tasks.registry import UnknownTaskError, default_family, families

METHODS = ("blind_bayes", "blind_robust", "probe_robust")
#: Sections of the flat YAML form that belong to the family's config.
TASK_SECTIONS = ("model", "simulator")

__all__ = ["ConfigError", "StudyConfig", "load_config", "parse_config", "dump_config"]


#: Most instances of a study (truths x contexts).
MAX_INSTANCES = 100_000


class InstancesConfig(_Strict):
    """Which ground-truth instances to draw."""

    split: str = Field("demo", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    count: int = Field(16, ge=1, le=100_000)
    sampling: Literal["uniform", "lhs"] = "uniform"
    seed: int = Field(0, ge=0)
    #: Truth box, if different from the model's prior box (the prior fault draws from +-12 mm).
    truth_low: tuple[float, ...] | None = None
    truth_high: tuple[float, ...] | None = None
    #: A fixed truth set (rows of latent values) instead of ``count`` draws from a box.
    truths: list[tuple[float, ...]] | None = Field(None, min_length=1, max_length=100_000)
    #: Observed contexts (targets) crossed with the truths: instance = (truth, context).
    contexts: list[tuple[float, ...]] | None = Field(None, min_length=1, max_length=10_000)

    @model_validator(mode="after")
    def _check(self) -> "InstancesConfig":
        if self.truths is not None and (self.truth_low is not None or self.truth_high is not None):
            raise _FieldError("truths", "give either a fixed truth set or a truth box, not both")
        for name in ("truths", "contexts"):
            rows = getattr(self, name)
            if rows is not None and len({len(r) for r in rows}) > 1:
                raise _FieldError(name, "every row must have the same number of coordinates")
        if self.truth_low is not None and self.truth_high is not None:
            if any(h <= lo for lo, h in zip(self.truth_low, self.truth_high)):
                raise _FieldError("truth_high", f"must be > truth_low in every coordinate, got {list(self.truth_high)} vs {list(self.truth_low)}")
        return self


class ProbesConfig(_Strict):
    """Probe schedule: ``random`` (i.i.d. uniform with replacement), a fixed list, or
    ``adaptive`` (each probe chosen by the current belief; beyond the paper)."""

    schedule: Union[Literal["random", "adaptive"], list[tuple[float, ...]]] = "random"
    budget: int = Field(8, ge=1, le=64)
    budgets: list[int] | None = Field(None, min_length=1)

    @field_validator("schedule", mode="before")
    @classmethod
    def _schedule(cls, value: Any) -> Any:
        # One clear message instead of pydantic's two union-branch errors.
        if value in ("random", "adaptive") and isinstance(value, str):
            return value
        if isinstance(value, (list, tuple)):
            out = []
            for i, v in enumerate(value):
                comps = list(v) if isinstance(v, (list, tuple)) else [v]
                if not comps or any(isinstance(c, bool) or not isinstance(c, Real) or not math.isfinite(c) for c in comps):
                    raise ValueError(f"probe {i} of the schedule must be a finite number or a list of them, got {v!r}")
                out.append(tuple(float(c) for c in comps))
            return out
        raise ValueError(f"must be 'random', 'adaptive' or a list of probes (numbers, or lists for vector probes), got {value!r}")

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
    #: ``jitter`` (the paper: clip-to-box jitter, biased) or ``mh`` (resample-move with a
    #: Metropolis-Hastings accept/reject, posterior-invariant).
    move: Literal["jitter", "mh"] = "jitter"
    move_steps: int = Field(1, ge=1, le=100)

    @model_validator(mode="after")
    def _check(self) -> "BeliefConfig":
        if self.mixture_high <= self.mixture_low:
            raise _FieldError("mixture_high", f"must be > mixture_low, got {self.mixture_high!r} <= {self.mixture_low!r}")
        return self


def _task_union() -> Any:
    members = tuple(spec.config for spec in families().values())
    if len(members) == 1:
        return members[0]
    return Annotated[Union[members], Field(discriminator="family")]


#: Every registered family's config, a discriminated union on ``family``. Built when this
#: module is imported, after the built-in families and the ``probecommit.tasks`` entry
#: points have registered; rebuilt by :func:`parse_config` when a family registers later.
TaskConfig = _task_union()
_UNION_OF: tuple[type, ...] = tuple(spec.config for spec in families().values())


class CalibrationConfig(_Strict):
    """How calibration constructs the set at a conformal threshold."""

    #: ``prefix``: the paper's top-weight prefix at t = 1 (its zero-weight plateau exception);
    #: ``hull``: every particle at t >= 1, so the conformal guarantee has no exception.
    plateau: Literal["prefix", "hull"] = "prefix"


class StudyConfig(_Strict):
    """One study: instances x repeats x probe schedule x budgets, one family's model, one engine.

    ``task`` is a discriminated union keyed on the family name over every registered
    family's config (:data:`TaskConfig`). In YAML the family's
    ``model`` and ``simulator`` sections may sit at the top level beside
    ``task: <family>`` (the flat form, also what :func:`dump_config` writes), or
    inside ``task: {family: ..., model: ..., simulator: ...}``.
    """

    name: str = Field("study", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    task: TaskConfig = None  # type: ignore[assignment]  # filled by _nest_task
    seed: int = Field(0, ge=0)
    repeats: int = Field(4, ge=1, le=1000)
    instances: InstancesConfig = InstancesConfig()
    probes: ProbesConfig = ProbesConfig()
    belief: BeliefConfig = BeliefConfig()
    calibration: CalibrationConfig = CalibrationConfig()
    methods: list[Literal["blind_bayes", "blind_robust", "probe_robust"]] = Field(list(METHODS), min_length=1)
    blind_prior_samples: int = Field(20_000, ge=100, le=10_000_000)
    #: Instances per work unit; a unit is the resumable, parallel grain.
    unit_instances: int = Field(4, ge=1, le=1000)

    @property
    def family(self) -> str:
        return self.task.family

    @property
    def model(self) -> Any:
        """The family's model section."""
        return self.task.model

    @property
    def simulator(self) -> Any:
        """The family's simulator section."""
        return self.task.simulator

    @model_validator(mode="before")
    @classmethod
    def _nest_task(cls, data: Any) -> Any:
        # The flat YAML form: ``task: <family>`` with ``model``/``simulator`` at the top.
        if not isinstance(data, dict):
            return data
        data = dict(data)
        task = data["task"] if "task" in data else default_family()
        if isinstance(task, str):
            task = {"family": task}
            for section in TASK_SECTIONS:
                if section in data:
                    task[section] = data.pop(section)
        elif isinstance(task, dict):
            clash = [s for s in TASK_SECTIONS if s in data]
            if clash:
                raise ValueError(f"'{clash[0]}' given both at the top level and inside 'task'; give it once")
        if isinstance(task, dict):
            name = task.get("family")
            known = families()
            if name not in known:
                raise _FieldError("task", f"unknown task family {name!r}; registered: {', '.join(sorted(known))}")
        data["task"] = task
        return data

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
        inst, task = self.instances, self.task
        if inst.truths is not None:
            n = len(task.latent_names)
            if n and len(inst.truths[0]) != n:
                raise _FieldError("instances.truths", f"rows need {n} coordinates ({', '.join(task.latent_names)}), got {len(inst.truths[0])}")
            # The family's limits hold for a fixed truth set as for a sampled box: its bounding box is checked.
            rows = list(zip(*inst.truths))
            task.check_truth_box(tuple(min(c) for c in rows), tuple(max(c) for c in rows), "instances.truths")
        else:
            low = inst.truth_low if inst.truth_low is not None else self.model.prior_low
            high = inst.truth_high if inst.truth_high is not None else self.model.prior_high
            task.check_truth_box(low, high, "instances")
            if any(h <= lo for lo, h in zip(low, high)):
                which = "truth_high" if inst.truth_high is not None else "truth_low"
                raise _FieldError(
                    f"instances.{which}",
                    f"truth box must have high > low in every coordinate, got low {list(low)}, high {list(high)} "
                    "(an unset end defaults to the model's prior box)",
                )
        n_ctx = len(task.context_names)
        if inst.contexts is not None and not n_ctx:
            raise _FieldError("instances.contexts", f"the {task.family} family has no context; remove instances.contexts")
        if inst.contexts is not None and len(inst.contexts[0]) != n_ctx:
            raise _FieldError("instances.contexts", f"rows need {n_ctx} coordinates ({', '.join(task.context_names) or 'the family has no context'}), got {len(inst.contexts[0])}")
        if n_ctx and inst.contexts is None:
            raise _FieldError("instances.contexts", f"the {task.family} family needs a context per instance ({', '.join(task.context_names)})")
        if inst.contexts is not None:
            task.check_contexts(inst.contexts, "instances.contexts")
        n_truths = len(inst.truths) if inst.truths is not None else inst.count
        n_instances = n_truths * (len(inst.contexts) if inst.contexts is not None else 1)
        if n_instances > MAX_INSTANCES:
            raise _FieldError("instances.contexts" if inst.contexts else "instances.count",
                              f"{n_truths} truths x {len(inst.contexts or [1])} contexts = {n_instances:,} instances, "
                              f"more than the {MAX_INSTANCES:,} a study may have")
        if isinstance(self.probes.schedule, list):
            bad = [p for p in self.probes.schedule if len(p) != task.probe_dim]
            if bad:
                raise _FieldError("probes.schedule", f"probes of the {task.family} family have {task.probe_dim} component(s), got {list(bad[0])}")
            import numpy as np

            from probecommit.tasks.registry import build_model

            grid = np.asarray(build_model(task).probe_grid, dtype=float)
            low, high = grid.min(axis=0), grid.max(axis=0)
            for i, probe in enumerate(self.probes.schedule):
                if np.any(np.asarray(probe) < low - 1e-9) or np.any(np.asarray(probe) > high + 1e-9):
                    raise _FieldError("probes.schedule", f"probe {i} = {list(probe)} is outside the {task.family} family's "
                                      f"probe range {low.tolist()} .. {high.tolist()}")
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
    # ``task.<family>.model.sigma`` -> ``model.sigma``: the flat form users write.
    if len(loc) >= 2 and loc[0] == "task" and loc[1] in families():
        loc = loc[2:] if len(loc) > 2 and loc[2] in TASK_SECTIONS else ["task"] + loc[2:]
    field = ".".join(loc) or "config"
    extra = f" (and {exc.error_count() - 1} more)" if exc.error_count() > 1 else ""
    return _one_line(f"invalid config field '{field}': {msg}{extra}")


def _refresh_task_union() -> None:
    """Rebuild :class:`StudyConfig`'s task union if a family registered after this module was
    imported (``register()`` in a user's script), so configs naming it validate."""
    global TaskConfig, _UNION_OF
    members = tuple(spec.config for spec in families().values())
    if members == _UNION_OF:
        return
    TaskConfig, _UNION_OF = _task_union(), members
    StudyConfig.model_fields["task"].annotation = TaskConfig
    StudyConfig.model_rebuild(force=True)


def parse_config(data: dict) -> StudyConfig:
    """Validate a config mapping.

    Raises:
        ConfigError: One line, ``invalid config field '<dotted.name>': <why>``,
            naming the first bad field (and how many more there are).
    """
    if not isinstance(data, dict):
        raise ConfigError(f"config must be a mapping of fields, got {type(data).__name__}")
    _refresh_task_union()
    try:
        return StudyConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_format_error(exc)) from None
    except (ValueError, TypeError, RecursionError) as exc:  # pragma: no cover - defensive
        raise ConfigError(_one_line(f"invalid config: {type(exc).__name__}: {exc}")) from None


def load_config(path: str | Path) -> StudyConfig:
    """Load and validate a YAML study config.

    An empty file is the default config; anything else must be a mapping.

    Raises:
        ConfigError: One line naming the file (unreadable, not YAML, duplicate key)
            or, from :func:`parse_config`, the bad field.
    """
    data = read_config_data(path)
    try:
        return parse_config(data)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def read_config_data(path: str | Path) -> dict:
    """A YAML config file's mapping, read but not validated (:func:`load_config` validates it;
    ``runner.overrides`` applies the overrides first, so a run validates its config once).

    Raises:
        ConfigError: One line naming the file (a folder, missing, unreadable, not YAML, not a mapping).
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path} is a directory, not a config file (give the YAML file inside it)")
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(_one_line(f"{path}: cannot read: {exc.strerror or exc}")) from None
    try:
        data = load_yaml(raw, str(path))  # size, node and depth budgets; safe tags; unique keys
    except YamlError as exc:
        raise ConfigError(str(exc)) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config must be a mapping of fields, got a YAML {type(data).__name__}")
    return data


def config_data(config: StudyConfig) -> dict[str, Any]:
    """The config as plain data in the flat form (``task: <family>``, then its sections)."""
    data = config.model_dump(mode="json")
    task = data.pop("task")
    data.update(task=task.pop("family"), **task)  # model, simulator
    order = ["name", "task", "seed", "repeats", "instances", "probes", "model", "belief", "simulator"]
    return {**{k: data[k] for k in order if k in data}, **{k: v for k, v in data.items() if k not in order}}


def dump_config(config: StudyConfig) -> str:
    """The config as YAML in the flat form; :func:`parse_config` reads it back identically."""
    return yaml.safe_dump(config_data(config), sort_keys=False)
