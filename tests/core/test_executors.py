"""Executors on hand-built cases with known answers, and the tie-break rule."""

import numpy as np

from probecommit.core.executors import (
    BlindBayes,
    ProbeRobust,
    prior_expected_loss,
    scenario_failure_fraction,
    scenario_max_loss,
    scenario_scores,
    select_action,
)
from probecommit.runner.build import blind_bayes_executor
from probecommit.tasks.insertion.model import InsertionModel


def _choose(model, theta, mask, reference_x):
    """Scenario executor on given scenarios: (index, score), tie-break against a reference x."""
    scores = scenario_scores(model, theta, mask)
    ref = np.stack([reference_x, np.ones_like(reference_x)], axis=-1)
    idx = select_action(scores, model.tie_break_cost(model.action_grid, ref))
    return idx, np.take_along_axis(scores, idx[:, None], axis=1)[:, 0]


def blind_bayes_action(model, seed, n):
    index, expected = blind_bayes_executor(model, seed, n).act_one()
    return float(model.action_grid[index, 0]), expected


def test_select_action_minimum_then_lowest_tie_cost_then_lowest_index():
    actions = np.array([0.0, 1.0, 2.0, 3.0])
    scores = np.array([[0.5, 0.1, 0.1, 0.1], [0.2, 0.2, 0.9, 0.9], [0.0, 0.3, 0.3, 0.0]])
    ref = np.array([2.2, 5.0, 1.5])
    cost = np.abs(actions[None, :] - ref[:, None])
    assert select_action(scores, cost).tolist() == [2, 1, 0]


def test_probe_robust_object_equals_scenario_scoring_on_its_retained_set():
    model = InsertionModel.deployed()
    rng = np.random.default_rng(3)
    particles = np.stack([rng.uniform(-10, 10, (5, 64)), rng.uniform(0.7, 1.3, (5, 64))], axis=-1)
    weights = rng.random((5, 64))
    weights /= weights.sum(axis=1, keepdims=True)
    chosen = ProbeRobust(model).act(particles, weights, 0.8)
    scores = scenario_scores(model, particles, chosen.mask)
    np.testing.assert_array_equal(chosen.score, scores.min(axis=1))
    assert np.all(chosen.mask.sum(axis=1) >= 1)


def test_scenario_failure_fraction_is_unweighted_over_retained():
    failures = np.array([[[True, False, True, True], [False, False, True, False]]])
    mask = np.array([[True, True, True, False]])
    np.testing.assert_allclose(scenario_failure_fraction(failures, mask), [[2 / 3, 1 / 3]])


def test_scenario_max_loss():
    losses = np.array([[[0.1, 0.9, 0.3], [0.5, 0.2, 0.4]]])
    mask = np.array([[True, False, True]])
    np.testing.assert_allclose(scenario_max_loss(losses, mask), [[0.3, 0.5]])
    np.testing.assert_allclose(prior_expected_loss(np.array([[0, 1], [1, 1]])), [0.5, 1.0])


def test_insertion_probe_robust_aims_at_the_retained_cluster():
    model = InsertionModel.deployed()
    # Three scenarios at x = 2.0 (c = 1 -> w = 1.7 mm), one outlier at -8: aim 2.0 fails only the outlier.
    theta = np.array([[[2.0, 1.0], [2.1, 1.0], [1.9, 1.0], [-8.0, 1.0]]])
    mask = np.ones((1, 4), dtype=bool)
    idx, score = _choose(model, theta, mask, np.array([2.0]))
    assert model.action_grid[idx[0], 0] == 2.0
    assert score[0] == 0.25
    # With the outlier dropped from the retained set the score is zero.
    idx, score = _choose(model, theta, np.array([[True, True, True, False]]), np.array([2.0]))
    assert model.action_grid[idx[0], 0] == 2.0 and score[0] == 0.0


def test_insertion_margin_shrinks_window():
    model = InsertionModel.deployed()
    theta = np.array([[[0.0, 1.0]]])  # w = 1.7
    assert not model.loss(np.array([1.5]), theta)[0, 0, 0]
    assert model.with_margin(0.8).loss(np.array([1.5]), theta)[0, 0, 0]  # 0.8 * 1.7 = 1.36


def test_blind_bayes_is_the_prior_optimum_and_deterministic():
    model = InsertionModel.deployed()
    a1, r1 = blind_bayes_action(model, 0, 20000)
    a2, r2 = blind_bayes_action(model, 0, 20000)
    assert (a1, r1) == (a2, r2)
    # Uniform prior on [-10, 10]: any aim at least w_max from the edges has P(fail) ~ 1 - 2*E[w]/20 = 0.83.
    assert abs(r1 - (1 - 2 * 1.7 / 20)) < 0.02
    assert abs(a1) <= 8.5


def test_interval_counting_equals_direct_counting():
    from probecommit.core.executors import interval_success_counts

    rng = np.random.default_rng(5)
    model = InsertionModel.deployed(margin=0.74)
    theta = np.stack([rng.uniform(-11, 11, (30, 200)), rng.uniform(0.7, 1.3, (30, 200))], axis=-1)
    # Put some interval ends exactly on grid points.
    theta[:, :20, 0] = np.round(theta[:, :20, 0] * 2) / 2
    mask = rng.random((30, 200)) < 0.7
    lo, hi = model.success_interval(theta)
    fast = interval_success_counts(lo, hi, mask, model.action_grid[:, 0])
    direct = np.sum(~model.loss(model.action_grid, theta) & mask[:, None, :], axis=-1)
    np.testing.assert_array_equal(fast, direct)


def test_probe_robust_scores_are_the_same_with_the_parts_formed_or_read_in_place(monkeypatch):
    """Insertion's affine parts read inside the compiled count give the commits and scores of the
    formed ``[E, N]`` parts (the path of a model without them), grown sets included."""
    model = InsertionModel.deployed(margin=0.83)
    rng = np.random.default_rng(8)
    particles = np.stack([rng.uniform(-10, 10, (20, 256)), rng.uniform(0.7, 1.3, (20, 256))], axis=-1)
    weights = rng.random((20, 256)) ** 4
    weights /= weights.sum(axis=1, keepdims=True)
    in_place = [ProbeRobust(model).act(particles, weights, t) for t in (0.8, 1.0, 1.2)]
    monkeypatch.setattr(InsertionModel, "success_interval_affine", lambda self: None)
    formed = [ProbeRobust(model).act(particles, weights, t) for t in (0.8, 1.0, 1.2)]
    for a, b in zip(in_place, formed):
        np.testing.assert_array_equal(a.index, b.index)
        np.testing.assert_array_equal(a.score, b.score)


def test_every_executor_implements_the_injected_interface_and_commit_calls_it():
    """ProbeRobust, BlindRobust and BlindBayes are ``Executor``s, and ``commit`` calls whatever
    executor it is given (no dispatch on method names): an injected one labels its own rows."""
    from dataclasses import dataclass

    from probecommit.core.executors import Belief, BlindBayes, BlindRobust, Commitment, Executor, ProbeRobust
    from probecommit.runner.build import build_executors, build_filter, build_model, build_simulator
    from probecommit.runner.inference import build_trace, commit, rollout
    from probecommit.runner.instances import draw_instances
    from tests.conftest import small_config

    model = InsertionModel()
    for executor in build_executors(["blind_bayes", "blind_robust", "probe_robust"], model, blind_prior_samples=50):
        assert isinstance(executor, Executor)
    assert [type(e) for e in build_executors(["probe_robust", "blind_bayes", "blind_robust"], model,
                                              blind_prior_samples=50)] == [BlindBayes, BlindRobust, ProbeRobust]

    @dataclass
    class FirstAim:
        """Always the first aim of the grid, on every budget."""
        model: object
        method = "first_aim"
        on_prior = False
        memo_tag = None

        def with_model(self, model):
            return FirstAim(model)

        def decide(self, belief: Belief, threshold, context=None, memo=None) -> Commitment:
            n = belief.weights.shape[0]
            mask = np.ones_like(belief.weights, dtype=bool)
            return Commitment(np.zeros(n, dtype=np.int64), np.full(n, 0.5), mask, belief.z.min(axis=1),
                              belief.z.max(axis=1))

    config = small_config(instances={"count": 2, "seed": 4}, probes={"budget": 2}, belief={"particles": 64}, repeats=1)
    model, simulator = build_model(config), build_simulator(config)
    batch = rollout(draw_instances(config, model), 1, "random", 2, model, simulator, config.seed)
    trace = build_trace(build_filter(model, config.belief), batch, config.seed, [1, 2])
    table = commit(trace, model, simulator, [FirstAim(model)], thresholds=0.8, margin=0.9)
    assert set(table["method"]) == {"first_aim"} and list(table["k"]) == [1, 2, 1, 2]
    assert np.all(table["action"] == model.action_grid[0, 0]) and np.all(table["predicted"] == 0.5)


def test_blind_bayes_answers_each_context_once_per_executor_and_the_same_as_computed_afresh():
    """A run's units share contexts: Blind-Bayes computes each once, and answers as a fresh executor would."""
    from probecommit.runner.build import build_model
    from probecommit.runner.config import load_config
    from probecommit.studies.breadth import PAPER_CONFIG_DIR

    model = build_model(load_config(PAPER_CONFIG_DIR / "push1d.yaml"))
    executor = blind_bayes_executor(model, 3, 200)
    calls = []
    act_one = executor.act_one
    executor.act_one = lambda context=None: calls.append(np.asarray(context).tolist()) or act_one(context)
    contexts = np.array([[0.5], [1.5], [0.5], [1.0]])
    first = executor.act(4, contexts)
    again = executor.act(2, contexts[[3, 1]])
    assert sorted(calls) == [[0.5], [1.0], [1.5]]  # each distinct context once, over both calls
    fresh = blind_bayes_executor(model, 3, 200)
    for got, rows in ((first, contexts), (again, contexts[[3, 1]])):
        want = [fresh.act_one(row) for row in rows]
        assert got[0].tolist() == [w[0] for w in want] and got[1].tolist() == [w[1] for w in want]


def test_a_tie_cost_that_reads_only_the_reference_is_computed_once_for_every_margin(monkeypatch):
    """Insertion declares its tie cost margin-free (``reads_only_reference``): the declaration holds (each
    margin's block the same bits) and ``_margin_ties`` computes one block; undeclared, one per margin."""
    from probecommit.core.executors import _margin_ties

    base = InsertionModel.deployed()
    models = [base.with_margin(g) for g in (0.5, 0.74, 1.0)]
    reference = np.random.default_rng(3).standard_normal((7, 2)) * 5
    per_margin = np.stack([m.tie_break_cost(m.action_grid, reference, None) for m in models])
    assert all(block.tobytes() == per_margin[0].tobytes() for block in per_margin)
    calls = []
    real = InsertionModel.tie_break_cost
    spy = lambda self, *args: calls.append(1) or real(self, *args)  # noqa: E731
    spy.reads_only_reference = True
    monkeypatch.setattr(InsertionModel, "tie_break_cost", spy)
    np.testing.assert_array_equal(_margin_ties(models, reference, None), per_margin[:1])
    assert len(calls) == 1
    del spy.reads_only_reference  # undeclared: every margin's block, found equal, one kept
    np.testing.assert_array_equal(_margin_ties(models, reference, None), per_margin[:1])
    assert len(calls) == 1 + len(models)
