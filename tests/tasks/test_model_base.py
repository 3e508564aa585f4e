"""TaskModelBase: the shared sigma/margin checks, with_margin and the default grown scenarios."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from probecommit.tasks.base import TaskModelBase
from probecommit.tasks.darts.model import DartsModel
from probecommit.tasks.grasp.model import GraspModel
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.tasks.planar_slide.model import PlanarSlideModel
from probecommit.tasks.push1d.model import Push1DModel
from probecommit.tasks.push2d.model import Push2DModel

FAMILIES = [DartsModel, GraspModel, InsertionModel, PlanarSlideModel, Push1DModel, Push2DModel]


@pytest.mark.parametrize("cls", FAMILIES)
def test_every_family_refuses_bad_sigma_and_margin_and_replaces_its_margin(cls):
    with pytest.raises(ValueError, match=r"^sigma must be positive, got -0.1$"):
        cls(sigma=-0.1)
    with pytest.raises(ValueError, match=r"^margin gamma must be in \(0, 1.5\], got 2.0$"):
        cls(margin=2.0)
    model = cls()
    tighter = model.with_margin(0.5)
    assert type(tighter) is cls and tighter.margin == 0.5 and model.margin == 1.0 and tighter.sigma == model.sigma


def test_a_model_without_a_margin_field_says_so():
    @dataclass(frozen=True)
    class NoMargin(TaskModelBase):
        name = "toy"

    with pytest.raises(NotImplementedError, match="the toy model has no execution margin"):
        NoMargin().with_margin(0.5)


def test_default_grown_scenarios_take_the_median_of_the_other_latents():
    from probecommit.tasks.insertion.model import InsertionModel

    rng = np.random.default_rng(0)
    particles, z_points = rng.standard_normal((6, 101, 2)), rng.standard_normal((6, 9))
    particles[1, 3, 0] = np.nan  # latent 0 is replaced by the points: its NaN does not matter
    particles[2, 4, 1] = np.nan  # a NaN in another latent propagates, as np.median does
    out = InsertionModel.deployed().grown_scenarios(particles, z_points)
    expected = np.repeat(np.median(particles, axis=1)[:, None, :], 9, axis=1)
    expected[..., 0] = z_points
    np.testing.assert_array_equal(out, expected)
    assert np.isnan(out[2, :, 1]).all() and not np.isnan(out[1]).any()


def _closed_form_interval(model, theta):
    """Each interval family's success interval as written before the parts existed (the paper's formulas)."""
    from probecommit.tasks.grasp.model import CRUSH_RATIO
    from probecommit.tasks.rig.model import RigModel, rig_window

    x, c = theta[..., 0], theta[..., 1]
    if isinstance(model, RigModel):
        window = model.margin * rig_window(c)
        return x - window, x + window
    if isinstance(model, InsertionModel):
        window = model.margin * (0.6 * c + 1.1)
        return x - window, x + window
    f_lift = model.decision(theta)
    centre, half = 0.5 * (1.0 + CRUSH_RATIO) * f_lift, 0.5 * (CRUSH_RATIO - 1.0) * f_lift * model.margin
    return centre - half, centre + half


@pytest.mark.parametrize("name", ["insertion", "rig", "grasp"])
@pytest.mark.parametrize("margin", [1.0, 0.8, 1.3])
def test_success_interval_is_its_parts_scaled_by_the_margin_bit_for_bit(name, margin):
    from probecommit.tasks.rig.model import RigModel

    model = {"insertion": InsertionModel, "rig": RigModel, "grasp": GraspModel}[name]().with_margin(margin)
    rng = np.random.default_rng(8)
    theta = rng.uniform(model.prior_low, model.prior_high, (6, 300, len(model.prior_low)))
    centre, half = model.success_interval_parts(theta)
    assert np.array_equal(model.with_margin(0.5).success_interval_parts(theta)[1], half)  # margin-free
    lo, hi = model.success_interval(theta)
    want_lo, want_hi = _closed_form_interval(model, theta)
    assert np.array_equal(lo, want_lo) and np.array_equal(hi, want_hi)
    width = half * margin
    assert np.array_equal(centre - width, lo) and np.array_equal(centre + width, hi)


def test_a_model_without_interval_parts_has_no_interval():
    assert Push1DModel().success_interval_parts(np.zeros((2, 3, 3))) is None
    assert Push1DModel().success_interval(np.zeros((2, 3, 3))) is None


def test_a_grown_sets_median_is_computed_once_per_belief_and_a_familys_own_points_stay_its_own(monkeypatch):
    """``grown_points`` keeps the default points' median in the belief's ``shared`` for its other thresholds
    (the same points as computed afresh); a family overriding ``grown_scenarios`` (1-D push) is called whole."""
    import probecommit.tasks.base as base
    from probecommit.core.executors import grown_points
    from probecommit.tasks.insertion.model import InsertionModel
    from probecommit.tasks.push1d.model import MIN_FRICTION, Push1DModel

    rng = np.random.default_rng(1)
    particles = rng.standard_normal((5, 64, 2))
    calls = []
    real = base.median_over_particles
    monkeypatch.setattr(base, "median_over_particles", lambda values: calls.append(1) or real(values))
    model, shared = InsertionModel.deployed(), {}
    for threshold in (1.2, 1.5, 1.2):
        kept = grown_points(model, particles, threshold, shared=shared)
        afresh = grown_points(model, particles, threshold)
        for a, b in zip(kept, afresh):
            np.testing.assert_array_equal(a, b)
    assert len(calls) == 1 + 3  # once for the shared belief, once per unshared call
    push = Push1DModel()  # its own grown_scenarios (friction kept positive), called whole with a shared belief
    assert not getattr(push.grown_scenarios, "takes_centre", False)
    grown, lo, _ = grown_points(push, push.sample_prior(rng, 128)[None], 30.0, shared={})
    assert lo[0] < 0 and grown[0, 0, 0] == MIN_FRICTION
