"""``check_family``: does a registered family honour the task contract? (like Gymnasium's
``check_env`` or scikit-learn's ``check_estimator``).

Built from the conformance suite the test suite used to hold: every check runs on a family's
default config and names the *declaration to fix* when it fails (``TaskSpec.name``, the
config's ``latent_names``, ``model.loss``, the simulator of an engine, ...), so a family
author reads what to change, not a stack trace. The suite runs it on every registered
family; ``probecommit tasks --check NAME`` runs it from the shell.

Checks, in order (a failed check that later checks depend on stops the run):

1. names agree: the spec's name, the config's ``family`` tag and the model's ``name``;
2. latents agree: the config's ``latent_names``/``context_names``/``probe_dim``, the model's,
   the prior box (shape, low < high, the config's prior);
3. positivity: a family declaring positive latents has a positive prior and refuses a
   truth box reaching zero or below;
4. model shapes: the ``TaskModel`` Protocol, grids, ``predict``, ``loss`` (boolean when binary,
   non-negative otherwise), ``decision``, ``tie_break_cost``, grown scenarios that map back;
5. margin: ``with_margin`` keeps the type and sets ``margin``;
6. executor: a one-particle belief commits to that particle's optimum; a grown set scored in
   blocks equals its scenarios scored at once;
7. filter: a particle filter updates on the model's shapes;
8. per installed engine: the simulator satisfies the Protocol, declares ``thread_safe``, reads
   ``observation_dim`` numbers and realizes an outcome; a small study gives identical episodes
   for the same seed and replays exactly (``study=True``).
"""

from __future__ import annotations

import importlib.util
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from probecommit.tasks.base import Simulator, TaskModel, TaskSpec


class FamilyCheckError(AssertionError):
    """A family failed :func:`check_family`; the message lists every failure with the declaration to fix."""


@dataclass
class FamilyReport:
    """What :func:`check_family` found.

    Attributes:
        family: The family's name.
        passed: Names of the checks that passed.
        failures: ``(check, declaration to fix, why)`` per failed check.
        skipped: ``(check, why)`` per check not run (an engine not installed, an earlier failure).
    """

    family: str
    passed: list[str] = field(default_factory=list)
    failures: list[tuple[str, str, str]] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def lines(self) -> list[str]:
        """One line per failure: ``check: fix <declaration>: why``."""
        return [f"{check}: fix {where}: {why}" for check, where, why in self.failures]


class _Failed(Exception):
    def __init__(self, where: str, why: str) -> None:
        super().__init__(why)
        self.where, self.why = where, why


def _expect(condition: bool, where: str, why: str) -> None:
    if not condition:
        raise _Failed(where, why)


def _deep_merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for key, value in extra.items():
        out[key] = _deep_merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def small_config(spec: TaskSpec, engine: str, name: str = "check") -> Any:
    """A small study config of ``spec`` in ``engine`` (2 instances x 2 repeats, budget 2, 64 particles)."""
    from probecommit.runner.config import parse_config

    data = {
        "name": name, "task": spec.name, "seed": 11, "repeats": 2,
        "instances": {"split": "conf", "count": 2, "seed": 5},
        "probes": {"schedule": "random", "budget": 2},
        "belief": {"particles": 64},
        "blind_prior_samples": 500,
    }
    return parse_config(_deep_merge(_deep_merge(data, spec.example), {"simulator": {"engine": engine}}))


def _context(model: Any, episodes: int, value: float) -> np.ndarray | None:
    return np.zeros((episodes, len(model.context_names))) + value if model.context_names else None


# ---------------------------------------------------------------------------------------------- checks
def _names(spec: TaskSpec, config: Any, model: Any) -> None:
    tag = getattr(config, "family", None)
    _expect(tag == spec.name, "the config class's `family` default",
            f"the config's family is {tag!r} but the spec is registered as {spec.name!r}")
    _expect(getattr(model, "name", None) == spec.name, "the model's `name`",
            f"build_model returns a model named {getattr(model, 'name', None)!r}, the spec is {spec.name!r}")


def _latents(spec: TaskSpec, config: Any, model: Any) -> None:
    declared = tuple(type(config).latent_names)
    _expect(len(declared) > 0, "the config class's `latent_names`", "declares no latents")
    _expect(tuple(model.latent_names) == declared, "the model's `latent_names` or the config's `latent_names`",
            f"the model has {tuple(model.latent_names)}, the config declares {declared}")
    _expect(tuple(model.context_names) == tuple(type(config).context_names),
            "the model's `context_names` or the config's `context_names`",
            f"the model has {tuple(model.context_names)}, the config declares {tuple(type(config).context_names)}")
    _expect(model.probe_dim == type(config).probe_dim, "the config's `probe_dim` or the model's `probe_grid`",
            f"the probe grid has {model.probe_dim} component(s), the config declares {type(config).probe_dim}")
    low, high = np.asarray(model.prior_low, float), np.asarray(model.prior_high, float)
    d = len(declared)
    _expect(low.shape == (d,) == high.shape, "the model's `prior_low`/`prior_high`",
            f"the prior box has shape {low.shape}/{high.shape}, the family has {d} latents {declared}")
    _expect(bool(np.all(high > low)), "the model's `prior_low`/`prior_high`", f"needs high > low, got {low} .. {high}")
    _expect(np.allclose(low, config.model.prior_low) and np.allclose(high, config.model.prior_high),
            "build_model (it must use the config's prior box)",
            f"the model's prior {low.tolist()} .. {high.tolist()} is not the config's "
            f"{list(config.model.prior_low)} .. {list(config.model.prior_high)}")
    _expect(np.asarray(model.jitter_scale).shape == (d,), "the model's `jitter_scale`",
            f"needs {d} entries, got shape {np.asarray(model.jitter_scale).shape}")


def _positivity(spec: TaskSpec, config: Any, model: Any) -> None:
    from probecommit.tasks.config import FieldError

    mask = np.asarray(type(config).positive_mask(), dtype=bool)
    if not mask.any():
        return
    low = np.asarray(model.prior_low, float)
    _expect(bool(np.all(low[mask] > 0)), "the prior box or the declared positivity",
            f"latents declared positive but the prior reaches {low.tolist()}")
    negative = tuple(-abs(v) if m else v for v, m in zip(config.model.prior_low, mask))
    try:
        config.check_truth_box(negative, tuple(config.model.prior_high), "instances")
    except FieldError:
        return
    raise _Failed("the config's `check_truth_box`", f"a negative truth box {list(negative)} was accepted "
                  "for latents declared positive")


def _shapes(spec: TaskSpec, config: Any, model: Any) -> None:
    missing = [name for name in TaskModel.__annotations__ if not hasattr(model, name)]
    missing += [name for name in ("predict", "loss", "decision", "tie_break_cost", "grown_scenarios", "with_margin",
                                  "success_interval", "success_interval_parts", "success_interval_affine",
                                  "sample_prior", "observation_range", "reading_levels") if not hasattr(model, name)]
    _expect(not missing, "the model class (subclass TaskModelBase)", f"lacks {', '.join(missing)}")
    _expect(isinstance(model, TaskModel), "the model class", "does not satisfy the TaskModel Protocol")
    P, A = np.asarray(model.probe_grid).shape, np.asarray(model.action_grid).shape
    _expect(len(P) == 2 and P[0] >= 1, "the model's `probe_grid`", f"must be [P, p] with P >= 1, got shape {P}")
    _expect(len(A) == 2 and A[0] >= 1, "the model's `action_grid`", f"must be [A, a] with A >= 1, got shape {A}")
    rng = np.random.default_rng(0)
    theta = np.stack([model.sample_prior(rng, 7) for _ in range(3)])
    _expect(bool(np.all((theta >= model.prior_low) & (theta <= model.prior_high))), "the model's `sample_prior`",
            "draws outside the prior box")
    u = np.asarray(model.probe_grid)[np.arange(3) % P[0]]
    y = np.asarray(model.predict(u, theta))
    _expect(y.shape == (3, 7, model.observation_dim), "the model's `predict`",
            f"must return [E, N, m] = (3, 7, {model.observation_dim}), got {y.shape}")
    _expect(bool(np.all(np.isfinite(y))), "the model's `predict`", "returns non-finite readings on the prior")
    context = _context(model, 3, 0.5)
    loss = np.asarray(model.loss(model.action_grid, theta, context))
    _expect(loss.shape == (3, A[0], 7), "the model's `loss`", f"must return [E, A, N] = (3, {A[0]}, 7), got {loss.shape}")
    if model.binary_loss:
        _expect(loss.dtype == bool, "the model's `loss` or `binary_loss`", f"a binary loss must be boolean, got {loss.dtype}")
    else:
        _expect(bool(np.all(loss >= 0)), "the model's `loss` or `binary_loss`", "a continuous loss must be >= 0")
    _expect(model.decision(theta).shape == (3, 7), "the model's `decision`", "must map [..., d] to [...]")
    _expect(model.tie_break_cost(model.action_grid, theta.mean(axis=1), context).shape == (3, A[0]),
            "the model's `tie_break_cost`", "must return [E, A]")
    z = model.decision(theta)
    points = z.min(axis=1, keepdims=True) + np.ptp(z, axis=1, keepdims=True) * np.linspace(0, 1, 9)
    grown = model.grown_scenarios(theta, points)
    _expect(grown.shape == (3, 9, theta.shape[2]), "the model's `grown_scenarios`", f"must return [E, 9, d], got {grown.shape}")
    _expect(np.allclose(model.decision(grown), points, rtol=1e-9, atol=1e-12),
            "the model's `grown_scenarios` (or `decision`)", "grown points do not map back to their decision coordinates")


def _margin(spec: TaskSpec, config: Any, model: Any) -> None:
    _expect(hasattr(model, "margin"), "the model's `margin` field", "the model has no execution margin")
    try:
        scaled = model.with_margin(0.8)
    except NotImplementedError as exc:
        raise _Failed("the model's `margin` dataclass field (or `with_margin`)", str(exc)) from None
    _expect(type(scaled) is type(model) and float(scaled.margin) == 0.8, "the model's `with_margin`",
            "must return the same model type with margin 0.8")


def _one_particle(spec: TaskSpec, config: Any, model: Any) -> None:
    from probecommit.core.executors import ProbeRobust

    rng = np.random.default_rng(1)
    theta = model.sample_prior(rng, 5)[:, None, :]
    context = _context(model, 5, 0.7)
    chosen = ProbeRobust(model).act(theta, np.ones((5, 1)), 0.8, context)
    loss = model.loss(model.action_grid, theta, context)[:, :, 0].astype(float)
    _expect(np.array_equal(chosen.score, loss.min(axis=1)), "the model's `loss` (or its success-interval fast path)",
            "a one-particle belief does not commit to that particle's optimum")


def _grown_blocks(spec: TaskSpec, config: Any, model: Any) -> None:
    from probecommit.core.executors import ProbeRobust, grown_set, retained_scores, scenario_scores

    for margin in (1.0, 0.8):
        scaled = model.with_margin(margin)
        rng = np.random.default_rng(2)
        theta = np.stack([scaled.sample_prior(rng, 40) for _ in range(4)])
        weights = rng.random((4, 40))
        weights /= weights.sum(axis=1, keepdims=True)
        context = _context(scaled, 4, 0.6)
        retained = ProbeRobust(scaled).retain(theta, weights, 1.3)
        scenarios, _, _ = grown_set(scaled, theta, 1.3)
        at_once = scenario_scores(scaled, scenarios, np.ones(scenarios.shape[:2], dtype=bool), context)
        _expect(np.array_equal(retained_scores(scaled, retained, context), at_once),
                "the model's `success_interval_parts`/`success_interval_affine` (they disagree with `loss`)",
                f"a grown set scored in blocks differs from its scenarios scored at once (margin {margin})")


def _filter(spec: TaskSpec, config: Any, model: Any) -> None:
    from probecommit.core.belief import ParticleFilter

    pf = ParticleFilter.gaussian(model, model.sigma, n_particles=32)
    rngs = [np.random.default_rng(i) for i in range(2)]
    state = pf.initial(rngs)
    u = np.asarray(model.probe_grid)[[0, -1]]
    y = model.predict(u, state.particles[:, :1])[:, 0]
    new = pf.update(state, u, y, rngs)
    _expect(new.particles.shape == state.particles.shape and bool(np.all(np.isfinite(new.log_weights).any(axis=1))),
            "the model's `predict` or `sigma`", "a particle filter update on the model's own readings fails")


def _simulator(spec: TaskSpec, engine: str, model: Any) -> None:
    from probecommit.tasks.registry import build_simulator

    where = f"the {engine!r} simulator ({spec.simulators[engine]})"
    sim = build_simulator(spec.name, small_config(spec, engine).task)
    _expect(isinstance(sim, Simulator), where, "does not satisfy the Simulator Protocol "
            "(subclass CachedSimulator/NoisySimulator; probe, execute, cache_records, load_cache, engine_calls)")
    _expect(sim.engine == engine, f"{where}'s `engine`", f"is {sim.engine!r}")
    _expect(isinstance(getattr(type(sim), "thread_safe", None), bool), f"{where}'s `thread_safe`",
            "must be declared True or False (True lets a study run its units in threads)")
    theta = model.sample_prior(np.random.default_rng(3), 1)[0]
    y = np.atleast_1d(sim.probe(theta, np.asarray(model.probe_grid)[0], np.random.default_rng(4)))
    _expect(y.shape == (model.observation_dim,) and bool(np.all(np.isfinite(y))), f"{where}'s `probe`",
            f"must return {model.observation_dim} finite number(s), got {y.tolist()}")
    context = _context(model, 1, 0.7)
    outcome = sim.execute(theta, np.asarray(model.action_grid)[0], None if context is None else context[0])
    _expect(isinstance(outcome, dict) and np.isfinite(float(outcome.get("realized", np.nan))), f"{where}'s `execute`",
            f"must return a dict with a finite 'realized', got {outcome!r}")


def _study(spec: TaskSpec, engine: str) -> None:
    import pandas as pd

    from probecommit.runner.replay import load_run, replay_episodes
    from probecommit.runner.study import run_study

    config = small_config(spec, engine)
    with tempfile.TemporaryDirectory(prefix="probecommit-check-") as tmp:
        a = run_study(config, Path(tmp) / "a").episodes
        b = run_study(config, Path(tmp) / "b").episodes
        _expect((a["status"] == "ok").all() and len(a) > 0, f"the {engine!r} simulator or `example`",
                "a small study has episodes that did not finish ok")
        _expect(a.equals(b), f"the {engine!r} simulator (draw every random number from the rng passed in)",
                "the same seed gave different episodes")
        replayed, _ = replay_episodes(load_run(Path(tmp) / "a"))
        try:
            pd.testing.assert_frame_equal(replayed.reset_index(drop=True), a.reset_index(drop=True), check_dtype=False)
        except AssertionError:
            raise _Failed(f"the {engine!r} simulator's cache (named queries must be pure functions)",
                          "a replay under the same model does not reproduce the episodes") from None


#: Engines that are packages to install, with the extra that installs each; any other engine name is
#: a family's own code (always runs).
ENGINE_EXTRAS = {"mujoco": "mujoco", "pybullet": "pybullet", "sapien": "sapien", "gymnasium": "gym"}
ENGINE_PACKAGES = tuple(ENGINE_EXTRAS)


def installed(engine: str) -> bool:
    """Whether an engine can run here: its package is importable (an engine of a family's own, such
    as ``analytic``, always can)."""
    return engine not in ENGINE_PACKAGES or importlib.util.find_spec(engine) is not None


MODEL_CHECKS: tuple[tuple[str, Callable[..., None]], ...] = (
    ("names", _names), ("latents", _latents), ("positivity", _positivity), ("shapes", _shapes),
    ("margin", _margin), ("one-particle optimum", _one_particle), ("grown set in blocks", _grown_blocks),
    ("filter", _filter),
)


#: Where a declared family fixes a failed check (its config, spec and defaults are derived).
DECLARED_FIXES = {
    "names": "the Declaration's `name` (and the model's base class: DeclaredModel)",
    "latents": "the Declaration's `latents`/`contexts`/`probe_grid`",
    "positivity": "the Declaration's `latents` (`positive=`, `low`)",
    "margin": "the Declaration's `margin` (and `loss` dividing by `self.margin`)",
    "build": "the Declaration or the model's constructor",
}


def check_family(family: str | TaskSpec, *, engines: Sequence[str] | None = None, study: bool = True,
                 raise_errors: bool = True) -> FamilyReport:
    """Check a family against the task contract.

    Args:
        family: A registered family's name, or a spec (registered or not: the study checks
            need it registered).
        engines: Engines to check (default: every engine of the family that is installed).
        study: Also run a small study twice and replay it (seconds per engine).
        raise_errors: Raise :class:`FamilyCheckError` listing every failure (else return the report).

    Raises:
        FamilyCheckError: one line per failure, each naming the declaration to fix.
    """
    from probecommit.tasks.registry import get

    spec = get(family) if isinstance(family, str) else family
    report = FamilyReport(spec.name)

    def run(name: str, check: Callable[..., None], *args: Any) -> bool:
        try:
            check(*args)
        except _Failed as exc:
            report.failures.append((name, exc.where, exc.why))
            return False
        except Exception as exc:  # noqa: BLE001 - a crash inside the family is a failure to report
            report.failures.append((name, "the family's code", f"raised {type(exc).__name__}: {exc}"))
            return False
        report.passed.append(name)
        return True

    built: dict[str, Any] = {}

    def build() -> None:
        built["config"] = spec.config()
        built["model"] = spec.build_model(built["config"])

    if not run("build", build):
        report.failures[-1] = ("build", "the config class's defaults or `build_model`", report.failures[-1][2])
    else:
        config, model = built["config"], built["model"]
        for name, check in MODEL_CHECKS:
            if not run(name, check, spec, config, model) and name in ("names", "latents", "shapes"):
                report.skipped.append(("the remaining checks", f"{name} failed"))
                break
        else:
            chosen = list(engines) if engines is not None else list(spec.engines)
            for engine in chosen:
                if engine not in spec.simulators:
                    report.failures.append((f"engine {engine}", "the spec's `simulators`", f"has no {engine!r} engine"))
                    continue
                if not installed(engine):
                    report.skipped.append((f"engine {engine}", f"{engine} is not installed"))
                    continue
                if run(f"simulator {engine}", _simulator, spec, engine, model) and study:
                    run(f"study {engine}", _study, spec, engine)
    if spec.declaration is not None:  # a declared family fixes these in its Declaration, not in derived code
        report.failures = [(check, DECLARED_FIXES.get(check, where), why) for check, where, why in report.failures]
    if raise_errors and report.failures:
        raise FamilyCheckError(f"family {spec.name!r} fails {len(report.failures)} check(s):\n  " + "\n  ".join(report.lines()))
    return report
