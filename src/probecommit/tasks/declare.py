"""A family is one declaration: latents, grids, decision coordinate, loss kind, margin, engines.

:func:`family` turns a :class:`Declaration` and a model class (a :class:`DeclaredModel`
subclass that writes only ``predict`` and ``loss``) into everything the rest of the package
reads: the pydantic config (``family`` tag, ``model`` and ``simulator`` sections with the
declared defaults and the latent checks), the :class:`~probecommit.tasks.base.TaskSpec` and
its registry entry, and, unless the declaration names its own, an ``analytic`` simulator
that reads the model's own prediction at the truth plus noise. Names, latents, units, the
prior box and positivity are written once; :func:`probecommit.check_family` checks that what
was derived agrees.

Put the declaration in ``tasks/<family>/__init__.py`` (a built-in family: the registry
imports every folder under ``tasks/``) or in your own package named by an entry point of
the ``probecommit.tasks`` group; ``family()`` registers it. See ``docs/adding-a-task.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, Mapping, Sequence

import numpy as np
from pydantic import Field, create_model

from probecommit.core.retained import median_over_particles
from probecommit.tasks.base import NoisySimulator, TaskModelBase, TaskSpec, as_rows
from probecommit.tasks.config import ModelConfigBase, SimulatorConfigBase, TaskConfigBase


@dataclass(frozen=True)
class Latent:
    """One latent coordinate.

    Attributes:
        name: Column name (``true_<name>`` in instance tables).
        unit: Unit, for people (``"kg"``, ``"mm"``, ``""``).
        low, high: The prior box along this coordinate (uniform prior).
        positive: A physical magnitude that must be > 0: truths and the prior are refused at or below zero.
        jitter: Post-resampling jitter standard deviation (default 2.5 % of the width).
    """

    name: str
    unit: str
    low: float
    high: float
    positive: bool = False
    jitter: float | None = None


@dataclass(frozen=True)
class Context:
    """One observed per-episode context component (a target distance): name, unit and the range
    an example study draws from (``low`` and ``high`` are its two example rows).

    ``limits`` is the open range the task can aim at at all (``None``: unbounded); every context a
    config gives, fixed or sampled, is checked against it (the config's ``context_ranges``)."""

    name: str
    unit: str
    low: float
    high: float
    limits: tuple[float, float] | None = None


@dataclass(frozen=True, eq=False)
class Declaration:
    """Everything about a family that generic code reads, written once.

    Attributes:
        name: Family name (the config's ``task``); a Python identifier.
        latents: The latent coordinates, in column order.
        probe_grid: Admissible probes ``[P]`` or ``[P, p]``.
        action_grid: Admissible commit actions ``[A]`` or ``[A, a]``.
        loss: ``"binary"`` (failure 0/1) or ``"continuous"`` (a miss, >= 0).
        sigma: The likelihood's reading noise (the model section's default).
        decision: Name of the decision-coordinate latent (default: the first). A model class of its
            own computes the coordinate in ``decision()``, which may be a function of several latents.
        contexts: Observed per-episode context components (a target), or none.
        margin: The execution margin's default (``model.margin``, in (0, 1.5]; 1 = none).
        noise_sigma: The simulator's reading noise default (default: ``sigma``).
        simulators: Engine -> ``"module:Class"`` (constructed as ``Class(noise_sigma=...)``);
            ``analytic`` is added from the model unless given.
        summary: Table II row (``probe``, ``action``, ``metric``, ...), for ``probecommit tasks``.
        example: Extra study-config fields of a small example study (contexts are added).
        default: The family a config naming no task runs (one family only).
        analytic: Add the ``analytic`` simulator that reads the model itself at the truth (a family
            whose model is its own ground truth); False for a family whose model is a surrogate
            or that names its own engines (the first engine of ``simulators`` is then the default).
        sigma_limit: Upper bound of ``model.sigma`` and ``simulator.noise_sigma`` a config may set.
        model_fields: Extra model-section fields, ``name -> (type, default or pydantic Field)``
            (a fitted factor the model takes as a keyword); they follow ``margin``.
        simulator_fields: Extra simulator-section fields, the same way; they follow ``noise_sigma``.
        doc: The config class's docstring (one line for people).
        model_order: The order the model section's fields are declared in, when not ``sigma``,
            ``margin``, the extra fields, the prior box. A dumped config lists ``sigma`` and the prior
            box (``ModelConfigBase``'s) first, then the rest in this order (insertion's ``boundary``
            and ``delta`` before ``margin``, as its frozen configs have them).
        engines_open: ``simulator.engine`` is any name, checked against the spec's engines when a
            config is validated (an engine added to the spec later is accepted; the message lists
            them); False: a ``Literal`` of the declared engines.
        model_base, simulator_base, config_base: Bases of the derived model section, simulator
            section and config (subclasses of ``ModelConfigBase``, ``SimulatorConfigBase`` and
            ``TaskConfigBase`` that add validators or override ``simulator_kwargs`` and
            ``check_truth_box``; they declare no fields: fields belong in the declaration).
        default_engine: The simulator section's default engine (default: the first engine).
        replay_shorthands, figure_guides: As :class:`~probecommit.tasks.base.TaskSpec`'s.
    """

    name: str
    latents: tuple[Latent, ...]
    probe_grid: Any
    action_grid: Any
    loss: Literal["binary", "continuous"]
    sigma: float
    decision: str | None = None
    contexts: tuple[Context, ...] = ()
    margin: float = 1.0
    noise_sigma: float | None = None
    simulators: Mapping[str, str] = field(default_factory=dict)
    summary: Mapping[str, str] = field(default_factory=dict)
    example: Mapping[str, Any] = field(default_factory=dict)
    default: bool = False
    analytic: bool = True
    sigma_limit: float = 1e6
    model_fields: Mapping[str, Any] = field(default_factory=dict)
    simulator_fields: Mapping[str, Any] = field(default_factory=dict)
    doc: str = ""
    model_order: tuple[str, ...] = ()
    engines_open: bool = False
    default_engine: str | None = None
    model_base: type = ModelConfigBase
    simulator_base: type = SimulatorConfigBase
    config_base: type = TaskConfigBase
    replay_shorthands: Mapping[str, str] = field(default_factory=dict)
    figure_guides: Any = None

    def __post_init__(self) -> None:
        problems = []
        if not self.name.isidentifier():
            problems.append(f"name {self.name!r} must be a Python identifier")
        if not self.latents:
            problems.append("declares no latents")
        names = [lat.name for lat in self.latents]
        if len(set(names)) != len(names):
            problems.append(f"latent names repeat: {names}")
        for lat in self.latents:
            if not lat.high > lat.low:
                problems.append(f"latent {lat.name!r} needs high > low, got {lat.low} .. {lat.high}")
            if lat.positive and lat.low <= 0:
                problems.append(f"latent {lat.name!r} is declared positive but its prior starts at {lat.low}")
        if self.decision is not None and self.decision not in names:
            problems.append(f"decision {self.decision!r} is not a latent ({', '.join(names)})")
        if self.loss not in ("binary", "continuous"):
            problems.append(f"loss must be 'binary' or 'continuous', got {self.loss!r}")
        if not 0 < self.sigma <= self.sigma_limit:
            problems.append(f"sigma must be in (0, sigma_limit={self.sigma_limit:g}], got {self.sigma}")
        clash = set(self.model_fields) & {"sigma", "margin", "prior_low", "prior_high"}
        clash |= set(self.simulator_fields) & {"engine", "noise_sigma", "execute_all_aims"}
        if clash:
            problems.append(f"model_fields/simulator_fields redeclare the derived field(s) {sorted(clash)}")
        if not 0 < self.margin <= 1.5:
            problems.append(f"margin must be in (0, 1.5], got {self.margin}")
        if problems:
            raise ValueError(f"declaration of family {self.name!r}: " + "; ".join(problems))

    # -------------------------------------------------------------------------------- derived
    @property
    def latent_names(self) -> tuple[str, ...]:
        return tuple(lat.name for lat in self.latents)

    @property
    def context_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.contexts)

    @property
    def decision_index(self) -> int:
        return self.latent_names.index(self.decision) if self.decision is not None else 0

    @property
    def prior_low(self) -> tuple[float, ...]:
        return tuple(float(lat.low) for lat in self.latents)

    @property
    def prior_high(self) -> tuple[float, ...]:
        return tuple(float(lat.high) for lat in self.latents)

    def probes(self) -> np.ndarray:
        grid = np.asarray(self.probe_grid, dtype=float)
        return as_rows(grid, 1 if grid.ndim == 1 else grid.shape[1], f"{self.name} probe_grid")

    def actions(self) -> np.ndarray:
        grid = np.asarray(self.action_grid, dtype=float)
        return as_rows(grid, 1 if grid.ndim == 1 else grid.shape[1], f"{self.name} action_grid")


class DeclaredModel(TaskModelBase):
    """Base of a declared family's model: everything but ``predict`` and ``loss`` comes from the declaration.

    A subclass writes ``predict(u[E, p], theta[E, N, d]) -> [E, N, m]`` and
    ``loss(actions[A, a], theta[E, N, d], context[E, c] | None) -> [E, A, N]`` (boolean failures
    for a binary loss; a miss divided by ``self.margin`` for a continuous one), reading
    ``self.margin``. Built by :func:`family` from the config's model section.
    """

    declaration: ClassVar[Declaration]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "loss" in cls.__dict__:
            cls.loss = _batched(cls.__dict__["loss"])

    def __init__(self, sigma: float, margin: float, prior_low: Any, prior_high: Any, variant: str = "deployed",
                 **fields: Any) -> None:
        decl = self.declaration
        self.name = decl.name
        self.variant = variant
        self.latent_names = decl.latent_names
        self.context_names = decl.context_names
        self.sigma, self.margin = float(sigma), float(margin)
        self.prior_low, self.prior_high = np.asarray(prior_low, float), np.asarray(prior_high, float)
        widths = self.prior_high - self.prior_low
        self.jitter_scale = np.array([lat.jitter if lat.jitter is not None else 0.025 * w
                                      for lat, w in zip(decl.latents, widths)])
        self.probe_grid, self.action_grid = decl.probes(), decl.actions()
        self.binary_loss = decl.loss == "binary"
        self.decision_domain_width = float(widths[decl.decision_index])
        self.extra = dict(fields)
        self.check_sigma_and_margin()

    def with_margin(self, gamma: float) -> "DeclaredModel":
        model = type(self).__new__(type(self))
        model.__dict__.update(self.__dict__)
        model.margin = float(gamma)
        return model

    def decision(self, theta: np.ndarray) -> np.ndarray:
        return np.asarray(theta)[..., self.declaration.decision_index]

    def grown_scenarios(self, particles: np.ndarray, z_points: np.ndarray) -> np.ndarray:
        """Each point at the particles' per-coordinate median, its decision coordinate set."""
        particles = np.asarray(particles)
        centre = median_over_particles(particles)
        extra = np.repeat(centre[:, None, :], z_points.shape[1], axis=1)
        extra[..., self.declaration.decision_index] = z_points
        return extra


class ModelSimulator(NoisySimulator):
    """The ``analytic`` simulator of a declared family: the model's own reading at the truth plus
    ``noise_sigma`` noise, and its loss at margin one as the realized outcome (named queries
    ``reading`` and ``outcome``, cached like any engine's)."""

    engine = "analytic"
    thread_safe = True
    family = "?"
    model_class: ClassVar[type]

    def __init__(self, noise_sigma: float) -> None:
        super().__init__(noise_sigma)
        decl = self.model_class.declaration
        self._truth = self.model_class(decl.sigma, 1.0, decl.prior_low, decl.prior_high)
        self._d = len(decl.latents)

    def reading(self, *values: float) -> np.ndarray:
        theta, u = np.asarray(values[:self._d]), np.asarray(values[self._d:])
        return np.asarray(self._truth.predict(u[None, :], theta[None, None, :]), float).reshape(-1)

    def outcome(self, *values: float) -> float:
        a = self._truth.action_dim
        theta, action, context = (np.asarray(values[:self._d]), np.asarray(values[self._d:self._d + a]),
                                  np.asarray(values[self._d + a:]))
        ctx = context[None, :] if context.size else None
        return float(np.asarray(self._truth.loss(action[None, :], theta[None, None, :], ctx), float).reshape(-1)[0])

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("reading", theta, np.ravel(u))
        return clean + self.noise_sigma * rng.standard_normal(clean.shape[0])

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if self._truth.context_names and context is None:
            raise ValueError(f"the {self.family} outcome needs the context ({', '.join(self._truth.context_names)})")
        arg = np.concatenate([np.ravel(action), np.ravel(context) if context is not None else []])
        return {"realized": float(self.cached("outcome", theta, arg)[0])}


def _batched(loss: Any) -> Any:
    """Let a family's ``loss(actions, theta[E, N, d], context[E, c])`` also take the prior-sample form
    the blind executor uses, ``theta[S, d]`` with one ``context[c]``, returning ``[A, S]``."""
    import functools

    @functools.wraps(loss)
    def wrapper(self, actions, theta, context=None):  # noqa: ANN001
        theta = np.asarray(theta, dtype=float)
        if theta.ndim == 2:
            ctx = None if context is None else np.asarray(context, dtype=float).reshape(1, -1)
            return loss(self, actions, theta[None], ctx)[0]
        return loss(self, actions, theta, None if context is None else np.asarray(context, dtype=float).reshape(theta.shape[0], -1))

    return wrapper


def _config_class(decl: Declaration) -> type:
    """The family's pydantic config, from the declaration (defaults, shapes, positivity)."""
    d = len(decl.latents)
    box = tuple[(float,) * d]  # type: ignore[misc]
    model_fields = {"sigma": (float, Field(decl.sigma, gt=0, le=decl.sigma_limit)),
                    "margin": (float, Field(decl.margin, gt=0, le=1.5)), **dict(decl.model_fields),
                    "prior_low": (box, decl.prior_low), "prior_high": (box, decl.prior_high)}
    if decl.model_order:
        if sorted(decl.model_order) != sorted(model_fields):
            raise ValueError(f"declaration of family {decl.name!r}: model_order {decl.model_order} must list the "
                             f"model section's fields {tuple(model_fields)}")
        model_fields = {name: model_fields[name] for name in decl.model_order}
    model_section = create_model(f"{decl.name}_model", __base__=decl.model_base, **model_fields)
    engines = tuple(dict.fromkeys((["analytic"] if decl.analytic else []) + list(decl.simulators)))
    if not engines:
        raise ValueError(f"declaration of family {decl.name!r}: no simulators and analytic=False")
    default_engine = decl.default_engine or engines[0]
    if default_engine not in engines:
        raise ValueError(f"declaration of family {decl.name!r}: default_engine {default_engine!r} is not one of {engines}")
    noise = decl.sigma if decl.noise_sigma is None else decl.noise_sigma
    engine = str if decl.engines_open else Literal[engines]  # type: ignore[valid-type]
    simulator_section = create_model(
        f"{decl.name}_simulator", __base__=decl.simulator_base, engine=(engine, default_engine),
        noise_sigma=(float, Field(noise, ge=0, le=decl.sigma_limit)), **dict(decl.simulator_fields),
    )
    positive = tuple(lat.positive for lat in decl.latents)


    config = create_model(
        f"{decl.name}_config", __base__=decl.config_base,
        family=(Literal[decl.name], decl.name),  # type: ignore[valid-type]
        model=(model_section, model_section()), simulator=(simulator_section, simulator_section()),
    )
    config.latent_names = decl.latent_names
    config.context_names = decl.context_names
    config.context_ranges = tuple(c.limits if c.limits is not None else (-float("inf"), float("inf"))
                                  for c in decl.contexts)
    config.probe_dim = decl.probes().shape[1]
    config.positive_latents = all(positive)
    config.latent_positive = positive
    config.__doc__ = decl.doc or f"Config of the declared family {decl.name!r}."
    return config


def family(decl: Declaration, model: type, *, register: bool = True, build_model: Any = None) -> TaskSpec:
    """The :class:`TaskSpec` of a declaration and its model class, registered (unless ``register=False``).

    Args:
        decl: The family's declaration.
        model: A :class:`DeclaredModel` subclass writing ``predict`` and ``loss``; or a model class
            of its own (a :class:`~probecommit.tasks.base.TaskModelBase` subclass built as
            ``Model(**model_section.model_kwargs())``, as the built-in families' are), which gets
            its ``name``, ``latent_names`` and ``context_names`` from the declaration.
        register: Add it to the registry (idempotent for the same family module).
        build_model: ``build_model(task_config) -> model``, where the model is not simply
            ``model(**task_config.model.model_kwargs())`` (a model section naming a variant).
    """
    from probecommit.tasks import registry

    if not (isinstance(model, type) and issubclass(model, TaskModelBase)):
        raise TypeError(f"family {decl.name!r}: the model must be a DeclaredModel (or TaskModelBase) subclass, got {model!r}")
    if issubclass(model, DeclaredModel):
        model.declaration = decl
    else:
        if decl.analytic and "analytic" not in decl.simulators:
            raise ValueError(f"declaration of family {decl.name!r}: a model of its own needs its engines named "
                             "in `simulators` (analytic=False)")
        model.name, model.latent_names, model.context_names = decl.name, decl.latent_names, decl.context_names
    config = _config_class(decl)
    simulators = dict(decl.simulators)
    if decl.analytic and "analytic" not in simulators:
        simulator = type(f"{decl.name}_analytic", (ModelSimulator,), {"model_class": model, "family": decl.name,
                                                                      "__module__": model.__module__})
        simulators = {"analytic": simulator, **simulators}

    def build(task_config: Any) -> Any:
        return model(**task_config.model.model_kwargs())

    example = dict(decl.example)
    if decl.contexts and "contexts" not in example.get("instances", {}):
        rows = [[c.low for c in decl.contexts], [c.high for c in decl.contexts]]
        example["instances"] = {**example.get("instances", {}), "contexts": rows}
    summary = {"latents": ", ".join(decl.latent_names), "metric": "failure" if decl.loss == "binary" else "miss",
               "sigma": f"{decl.sigma:g}", **decl.summary}
    spec = TaskSpec(name=decl.name, config=config, build_model=build_model or build, simulators=simulators, summary=summary,
                    example=example, default=decl.default, replay_shorthands=dict(decl.replay_shorthands),
                    figure_guides=decl.figure_guides, declaration=decl)
    if register:
        # A declared family registered again (its module re-imported, a notebook cell re-run) replaces itself.
        registry.register(spec, replace=registry.registered(decl.name, declared=True))
    return spec


def as_grid(values: Sequence[Any]) -> tuple:
    """A grid as nested tuples (a frozen declaration holds no arrays)."""
    return tuple(tuple(map(float, np.atleast_1d(v))) for v in values)
