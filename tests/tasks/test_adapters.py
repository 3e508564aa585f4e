"""Adapters: a family from plain functions and a family from a Gymnasium MuJoCo environment each pass
check_family, run a study and are audited; the surrogate's interpolation is exact where it must be."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from probecommit.audit.pipeline import audit
from probecommit.runner.config import parse_config
from probecommit.runner.family_check import check_family
from probecommit.runner.study import run_study
from probecommit.tasks.adapters.functions import function_family
from probecommit.tasks.adapters.gym import interpolate
from probecommit.tasks.declare import Context, Latent
from probecommit.tasks.registry import unregister

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
G = 9.81


def slide(th, impulse):
    """Coulomb slide distance of a box of friction th[..., 0] and mass th[..., 1] after an impulse."""
    return (impulse / th[..., 1]) ** 2 / (2 * th[..., 0] * G)


@pytest.fixture(scope="module")
def function_spec():
    yield function_family(
        "fn_slide", latents=[Latent("mu", "", 0.2, 0.6, positive=True), Latent("m", "kg", 0.5, 1.5, positive=True)],
        predict=lambda th, u: slide(th, u[..., 0]),
        loss=lambda th, a, target: np.abs(slide(th, a[..., 0]) - target[..., 0]),
        probe_grid=[1.0, 2.0], action_grid=np.round(np.linspace(0.5, 5.0, 91), 6), sigma=0.05,
        contexts=[Context("target", "m", 0.5, 1.5)])
    unregister("fn_slide")  # later tests see only the built-in families


def small_study(tmp_path, family: str, contexts) -> Path:
    config = parse_config({"name": family, "task": family, "seed": 2, "repeats": 2,
                           "instances": {"count": 4, "contexts": contexts},
                           "probes": {"schedule": "random", "budget": 2}, "belief": {"particles": 256},
                           "blind_prior_samples": 500})
    run_study(config, tmp_path / family)
    return tmp_path / family


def test_a_function_family_passes_the_checker_runs_and_is_audited(function_spec, tmp_path):
    report = check_family("fn_slide")
    assert "study analytic" in report.passed and report.ok
    model = function_spec.build_model(function_spec.config())
    theta = np.array([[[0.4, 1.0]]])
    np.testing.assert_allclose(model.predict(np.array([[2.0]]), theta)[0, 0, 0], 4 / (2 * 0.4 * G), rtol=1e-15)
    run = small_study(tmp_path, "fn_slide", [[1.0]])
    table = audit(run, resamples=100).table
    assert set(table["method"]) == {"blind_bayes", "blind_robust", "probe_robust"}
    assert table["coverage"].between(0, 1).all() and (table["n_episodes"] == 8).all()


def test_a_function_family_declared_with_a_negative_positive_latent_is_refused():
    with pytest.raises(ValueError, match="latent 'mu' is declared positive but its prior starts at -0.1"):
        function_family("fn_bad", latents=[Latent("mu", "", -0.1, 0.6, positive=True)], predict=lambda th, u: th[..., 0],
                        loss=lambda th, a, c: np.abs(th[..., 0] - a[..., 0]), probe_grid=[1.0], action_grid=[0.0, 1.0],
                        sigma=0.1, register=False)


def test_multilinear_interpolation_is_exact_for_a_multilinear_function():
    low, high = np.array([0.0, 1.0]), np.array([2.0, 5.0])
    a, b = np.meshgrid(np.linspace(0, 2, 5), np.linspace(1, 5, 3), indexing="ij")
    table = np.stack([3 * a + 2 * b - a * b, a], axis=-1)  # [5, 3, 2]
    theta = np.array([[[0.3, 4.1], [2.0, 1.0], [9.0, 3.0]]])  # the last is clipped to the box
    out = interpolate(table, low, high, theta)
    x, y = np.minimum(theta[..., 0], 2.0), theta[..., 1]
    np.testing.assert_allclose(out[..., 0], 3 * x + 2 * y - x * y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[..., 1], x, rtol=0, atol=1e-12)


@pytest.mark.mujoco
def test_a_gymnasium_mujoco_family_passes_the_checker_runs_and_is_audited(tmp_path):
    if importlib.util.find_spec("gymnasium") is None or importlib.util.find_spec("mujoco") is None:
        pytest.skip("gymnasium or mujoco not installed (pip install 'probecommit[gym]')")
    sys.path.insert(0, str(EXAMPLES))
    try:
        import gym_reacher_family  # noqa: F401 - registers gym_reacher
    finally:
        sys.path.remove(str(EXAMPLES))
    try:
        report = check_family("gym_reacher")
        assert report.ok and "study gymnasium" in report.passed
        run = small_study(tmp_path, "gym_reacher", [[0.5], [1.0]])
        table = audit(run, resamples=100).table
    finally:
        unregister("gym_reacher")
        sys.modules.pop("gym_reacher_family", None)
    probed = table.loc[table["method"] == "probe_robust"]
    assert len(probed) == 2 and (probed["n_episodes"] == 16).all()
    # The probes identify the damping: the committed torque misses less after two probes than blind.
    blind = float(table.loc[table["method"] == "blind_bayes", "realized"].iloc[0])
    assert float(probed.loc[probed["k"] == 2, "realized"].iloc[0]) < blind
