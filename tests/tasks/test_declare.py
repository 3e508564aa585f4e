"""The built-in families are declarations, and what a built-in needs of a declaration works:
own model classes, extra section fields and their order, open engines, a default engine."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import Field, ValidationError

from probecommit.tasks.base import TaskModelBase
from probecommit.tasks.config import FieldError
from probecommit.tasks.declare import Declaration, DeclaredModel, Latent, family
from probecommit.tasks.registry import builtin_packages, families, unregister


def _builtins():
    return [name for name in builtin_packages() if name in families()]


def test_every_builtin_family_is_one_declaration():
    assert len(_builtins()) == 9
    for name in _builtins():
        spec = families()[name]
        decl = spec.declaration
        assert decl is not None and decl.name == name, name
        config = spec.config()
        model = spec.build_model(config)
        assert tuple(model.latent_names) == decl.latent_names == tuple(spec.config.latent_names), name
        assert tuple(model.context_names) == decl.context_names == tuple(spec.config.context_names), name
        assert config.model.prior_low == decl.prior_low and config.model.prior_high == decl.prior_high, name
        assert spec.config.positive_mask() == tuple(lat.positive for lat in decl.latents), name
        assert np.array_equal(model.probe_grid, decl.probes()) and np.array_equal(model.action_grid, decl.actions()), name
        assert spec.engines == tuple(decl.simulators), name


def test_the_paper_defaults_survive_the_derivation():
    # Hand values of the frozen configs before the declaration: a change here changes published numbers.
    insertion = families()["insertion"].config()
    assert (insertion.model.boundary, insertion.model.sigma, insertion.simulator.engine) == ("deployed", 0.5, "mujoco")
    assert list(type(insertion.model).model_fields) == ["sigma", "prior_low", "prior_high", "boundary", "delta", "margin"]
    rig = families()["rig"].config()
    assert (rig.simulator.engine, rig.simulator.noise_sigma, rig.simulator.misread_rate) == ("mujoco", 0.0, 0.01)
    assert families()["push2d"].config().model.mu_scale == 1.0019
    assert families()["grasp"].config().simulator.engine == "mujoco"
    with pytest.raises(ValidationError, match="less than or equal to 10"):
        families()["push1d"].config.model_validate({"model": {"sigma": 11}})


class _Line(DeclaredModel):
    def predict(self, u, theta):
        return theta[..., :1] * u[:, None, :]

    def loss(self, actions, theta, context):
        return np.abs(theta[:, None, :, 0] - actions[None, :, None, 0]) / self.margin


def _decl(**changes):
    base = dict(name="line_decl", latents=(Latent("k", "", 1.0, 2.0, positive=True),), probe_grid=[1.0, 2.0],
                action_grid=[1.0, 1.5, 2.0], loss="continuous", sigma=0.1)
    return Declaration(**{**base, **changes})


def test_extra_fields_follow_margin_unless_an_order_is_declared():
    extra = {"gain": (float, Field(2.0, gt=0))}
    plain = family(_decl(model_fields=extra), _Line, register=False).config
    assert list(plain.model_fields["model"].annotation.model_fields) == ["sigma", "prior_low", "prior_high", "margin", "gain"]
    ordered = family(_decl(model_fields=extra, model_order=("gain", "sigma", "margin", "prior_low", "prior_high")),
                     _Line, register=False).config
    assert list(ordered.model_fields["model"].annotation.model_fields) == ["sigma", "prior_low", "prior_high", "gain", "margin"]
    with pytest.raises(ValueError, match="model_order"):
        family(_decl(model_fields=extra, model_order=("sigma", "margin")), _Line, register=False)
    with pytest.raises(ValueError, match="redeclare the derived field"):
        _decl(model_fields={"sigma": (float, 1.0)})


@pytest.fixture()
def registered():
    """Configs check their engine against the registry: register the test family, then remove it."""
    yield
    if "line_decl" in families():
        unregister("line_decl")


def test_default_engine_and_open_engines(registered):
    sims = {"analytic": "probecommit.tasks.push1d.sim_analytic:AnalyticPush1DSimulator",
            "other": "probecommit.tasks.push1d.sim_analytic:AnalyticPush1DSimulator"}
    spec = family(_decl(simulators=sims, analytic=False, default_engine="other"), _Line)
    assert spec.config().simulator.engine == "other"
    with pytest.raises(ValueError, match="default_engine 'nope'"):
        family(_decl(simulators=sims, analytic=False, default_engine="nope"), _Line, register=False)
    closed = spec.config.model_fields["simulator"].annotation
    with pytest.raises(ValidationError):
        closed(engine="later")
    opened = family(_decl(simulators=sims, analytic=False, engines_open=True), _Line).config
    assert opened.model_fields["simulator"].annotation(engine="later").engine == "later"
    with pytest.raises(ValidationError, match="has no 'later' simulator; it has: analytic, other"):
        opened.model_validate({"simulator": {"engine": "later"}})  # the whole config checks it against the spec


def test_a_model_class_of_its_own_takes_its_names_from_the_declaration(registered):
    @dataclasses.dataclass(frozen=True)
    class Own(TaskModelBase):
        sigma: float = 0.1
        margin: float = 1.0
        prior_low: np.ndarray = dataclasses.field(default_factory=lambda: np.array([1.0]))
        prior_high: np.ndarray = dataclasses.field(default_factory=lambda: np.array([2.0]))

    sims = {"analytic": "probecommit.tasks.push1d.sim_analytic:AnalyticPush1DSimulator"}
    spec = family(_decl(simulators=sims, analytic=False), Own)
    model = spec.build_model(spec.config())
    assert (model.name, model.latent_names, model.context_names) == ("line_decl", ("k",), ())
    with pytest.raises(ValueError, match="needs its engines named"):
        family(_decl(), Own, register=False)
    with pytest.raises(TypeError, match="DeclaredModel"):
        family(_decl(), object, register=False)


@settings(max_examples=40, deadline=None)
@given(low=st.tuples(st.floats(-5, 5), st.floats(-5, 5)))
def test_positivity_is_checked_per_latent_by_the_base_rule(low):
    """One rule (``TaskConfigBase.check_truth_box`` over ``positive_mask()``) for every family:
    a non-positive start is refused exactly on the latents declared positive, and named."""
    decl = _decl(name="mixed_decl", latents=(Latent("k", "", 1.0, 2.0, positive=True), Latent("b", "", -1.0, 1.0)))
    config = family(decl, _Line, register=False).config
    assert config.positive_mask() == (True, False)
    high = tuple(v + 1.0 for v in low)
    if low[0] <= 0:
        with pytest.raises(FieldError, match=r"truth_low.*\bk must be positive") as err:
            config.model_construct().check_truth_box(low, high, "truths")
        assert " b " not in str(err.value) and "b must" not in str(err.value)
    else:
        config.model_construct().check_truth_box(low, high, "truths")
