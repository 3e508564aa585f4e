"""Blind-Bayes's prior expected loss over blocks of actions, and Probe-Robust's minimax scores over blocks of
scenarios, are the whole arrays' answers bit for bit
(issue 42: the whole ``[actions, prior sample]`` matrix set the breadth target's memory peak)."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.core.executors import blocked_prior_expected_loss, prior_expected_loss
from probecommit.runner.build import build_model, config_executors
from probecommit.studies.breadth import paper_config


@pytest.mark.parametrize("family", ["push2d", "darts", "push1d", "hinge", "grasp", "shuffleboard"])
def test_blocks_give_the_whole_matrix_answer(family: str) -> None:
    config = paper_config(family)
    model = build_model(config)
    blind = next(e for e in config_executors(config, model) if e.method == "blind_bayes")
    sample = blind.prior_sample[:257]
    contexts = getattr(config.instances, "contexts", None) or [None]
    for context in contexts[:2]:
        context = None if context is None else np.asarray(context, dtype=float)
        whole = prior_expected_loss(model.loss(model.action_grid, sample, context))
        for rows in (1, 2, 3, 7, 64, len(model.action_grid)):
            blocked = blocked_prior_expected_loss(model, sample, context, block_bytes=rows * 8 * len(sample))
            assert blocked.shape == whole.shape
            assert blocked.tobytes() == whole.tobytes(), (family, context, rows)


def test_blocks_are_never_one_action_alone() -> None:
    """A one-row block (a model's ``actions @ target`` through BLAS's vector path) rounds differently."""
    seen: list[int] = []

    class Model:
        action_grid = np.arange(5.0)[:, None]

        def loss(self, actions, theta, context=None):
            seen.append(len(actions))
            return np.abs(actions - theta[None, :, 0])

    out = blocked_prior_expected_loss(Model(), np.zeros((4, 1)), block_bytes=8 * 4)
    assert min(seen) >= 2 and sum(seen) == 5
    assert out.tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]


@pytest.mark.parametrize("family", ["push2d", "darts", "push1d", "hinge", "shuffleboard"])
def test_scenario_blocks_give_the_whole_array_scores(family: str) -> None:
    """Probe-Robust's minimax scores over scenario blocks are the whole ``[E, A, N]`` array's, bit for bit."""
    from probecommit.core.executors import blocked_max_loss, scenario_max_loss

    config = paper_config(family)
    model = build_model(config)
    rng = np.random.default_rng(7)
    episodes, n = 3, 61
    scenarios = model.sample_prior(rng, episodes * n).reshape(episodes, n, -1)
    mask = rng.random((episodes, n)) < 0.6
    mask[1] = False  # an episode retaining nothing: -inf either way
    contexts = getattr(config.instances, "contexts", None)
    context = None if not contexts else np.asarray(contexts[:episodes], dtype=float)
    whole = scenario_max_loss(model.loss(model.action_grid, scenarios, context), mask)
    for step in (1, 2, 7, 60):
        blocked = blocked_max_loss(model, scenarios, mask, context,
                                   block_bytes=step * 8 * episodes * len(model.action_grid))
        assert blocked.tobytes() == whole.tobytes(), (family, step)
