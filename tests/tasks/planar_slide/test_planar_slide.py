"""The example family end to end: run, replay, audit and calibrate from the command line.

planar_slide has a 3-D latent, a 2-D observation, a 2-D action and a per-instance
target, so this proves the pipeline carries vectors and context without special cases.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import yaml
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.tasks.planar_slide.model import PlanarSlideModel, rest_position
from probecommit.tasks.planar_slide.sim_analytic import AnalyticPlanarSlideSimulator


def config(split: str, seed: int) -> dict:
    return {
        "name": f"slide-{split}", "task": "planar_slide", "seed": 3, "repeats": 2,
        "instances": {"split": split, "count": 6, "seed": seed, "contexts": [[1.0, 0.2], [0.6, -0.3]]},
        "probes": {"schedule": "random", "budget": 4, "budgets": [1, 4]},
        "belief": {"particles": 128}, "blind_prior_samples": 1000,
    }


def test_noise_free_simulator_equals_the_model():
    model, sim = PlanarSlideModel(), AnalyticPlanarSlideSimulator(noise_sigma=0.0)
    theta = np.array([0.4, 0.1, 1.2])
    for u in model.probe_grid:
        np.testing.assert_allclose(sim.probe(theta, u, np.random.default_rng(0)),
                                   model.predict(u[None], theta[None, None])[0, 0], rtol=1e-12)
    target = np.array([1.0, 0.2])
    best = model.loss(model.action_grid, theta[None, None], target[None])[0, :, 0]
    i = int(np.argmin(best))
    assert sim.execute(theta, model.action_grid[i], target)["realized"] == best[i]
    # A strike straight along +x with no bias slides |J|^2 / (2 g mu m^2).
    np.testing.assert_allclose(rest_position(np.array([2.0, 0.0]), 0.5, 0.0, 1.0), [4 / (2 * 9.81 * 0.5), 0.0])


def test_run_replay_audit_calibrate_end_to_end(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    for split, seed in (("cal", 1), ("test", 2)):
        (tmp_path / f"{split}.yaml").write_text(yaml.safe_dump(config(split, seed)))
        result = runner.invoke(app, ["run", f"{split}.yaml", "-o", split])
        assert result.exit_code == 0, result.output
    episodes = pd.read_parquet(tmp_path / "test" / "episodes.parquet")
    assert {"action_0", "action_1"} <= set(episodes.columns) and "action" not in episodes.columns
    assert set(episodes["method"]) == {"blind_bayes", "blind_robust", "probe_robust"}
    probes = pd.read_parquet(tmp_path / "test" / "probes.parquet")
    assert {"u", "y_0", "y_1"} <= set(probes.columns)
    instances = pd.read_parquet(tmp_path / "test" / "instances.parquet")
    assert {"true_mu", "true_phi", "true_m", "ctx_target_x", "ctx_target_y"} <= set(instances.columns)
    # Probes cut the miss at a fixed executor (Blind-Robust -> Probe-Robust(4)).
    miss = episodes.groupby(["method", "k"])["realized"].mean()
    assert miss[("probe_robust", 4)] < miss[("blind_robust", 0)]

    result = runner.invoke(app, ["replay", "test", "--set", "model.sigma=0.02", "-o", "again"])
    assert result.exit_code == 0, result.output
    again = pd.read_parquet(tmp_path / "again" / "episodes.parquet")
    pd.testing.assert_frame_equal(again, episodes)  # same model -> identical episodes

    result = runner.invoke(app, ["audit", "test"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "test-audit" / "audit.html").is_file()
    result = runner.invoke(app, ["calibrate", "--cal", "cal", "--test", "test"])
    assert result.exit_code == 0, result.output
    assert "set calibration" in result.output
