"""Adaptive probes: chosen by the belief, reproducible, and never silently compared as paired."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.core.selectors import expected_posterior_variance
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.runner.study import run_study
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.core.likelihood import GaussianLikelihood
from tests.conftest import small_config


def test_the_selector_prefers_the_probe_that_splits_the_belief():
    model = InsertionModel.deployed()
    # Half the mass at x = -6, half at x = +6: a tap at +6 separates them, a tap at -12 or +12 tells nothing.
    particles = np.array([[[-6.0, 1.0]] * 50 + [[6.0, 1.0]] * 50])
    weights = np.full((1, 100), 0.01)
    scores = expected_posterior_variance(model, GaussianLikelihood(0.5), particles, weights, model.probe_grid)
    grid = model.probe_grid[:, 0]
    assert scores[0, grid == 6.0] < 1e-6 and scores[0, grid == -6.0] < 1e-6
    assert scores[0, grid == 12.0] == pytest.approx(36.0) and scores[0, grid == -12.0] == pytest.approx(36.0)


@pytest.fixture(scope="module")
def adaptive_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("adaptive")
    config = small_config(name="adaptive", probes={"schedule": "adaptive", "budget": 4}, belief={"particles": 256})
    return config, run_study(config, out / "run"), out


def test_adaptive_runs_are_deterministic_and_replay_exactly(adaptive_run, tmp_path):
    config, result, _ = adaptive_run
    again = run_study(config, tmp_path / "again")
    pd.testing.assert_frame_equal(result.episodes, again.episodes)
    replayed, _ = replay_episodes(load_run(result.run_dir))
    pd.testing.assert_frame_equal(replayed.reset_index(drop=True), result.episodes.reset_index(drop=True), check_dtype=False)


def test_adaptive_probes_beat_random_on_posterior_variance(adaptive_run, tmp_path):
    config, result, _ = adaptive_run
    random = run_study(small_config(name="random", probes={"budget": 4}, belief={"particles": 256}), tmp_path / "r")
    var = lambda ep: ep[(ep.method == "probe_robust") & (ep.k == 4)]["post_var"].mean()  # noqa: E731
    assert var(result.episodes) < var(random.episodes)


def test_a_replay_under_another_model_is_refused_unless_asked(adaptive_run):
    _, result, _ = adaptive_run
    loaded = load_run(result.run_dir)
    with pytest.raises(ValueError, match="not a paired"):
        replay_episodes(loaded, {"model": {"boundary": "corrected"}})
    episodes, _ = replay_episodes(loaded, {"model": {"boundary": "corrected"}}, fixed_probes=True)
    assert set(episodes["variant"]) == {"corrected"}


def test_scores_a_block_of_episodes_at_a_time_equal_the_whole_batch_bit_for_bit():
    """The adaptive rollout scores blocks of episodes to bound its memory; no score may change."""
    from probecommit.runner.inference import adaptive_scores

    model = InsertionModel.deployed()
    rng = np.random.default_rng(5)
    particles = np.stack([rng.uniform(-12, 12, (7, 64)), rng.uniform(0.5, 2.0, (7, 64))], axis=-1)
    weights = rng.random((7, 64))
    weights /= weights.sum(axis=1, keepdims=True)
    likelihood = GaussianLikelihood(0.5)
    whole = expected_posterior_variance(model, likelihood, particles, weights, model.probe_grid)
    for elements in (1, 32 * 64 * 2, 32 * 64 * 3, 1 << 30):  # blocks of 1, 2, 3 and all 7 episodes
        np.testing.assert_array_equal(adaptive_scores(model, likelihood, particles, weights, model.probe_grid,
                                                      elements), whole)
