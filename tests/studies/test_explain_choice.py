"""Hand cases for the development-search stability statistic (E31, E32)."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.studies.explain.choice import choice_stability, winners


def test_winners_break_ties_by_secondary_then_first_column():
    assert winners(np.array([[0.2, 0.1, 0.1]])).tolist() == [1]
    assert winners(np.array([[0.1, 0.1, 0.1]]), np.array([[3.0, 1.0, 1.0]])).tolist() == [1]
    assert winners(np.array([[0.1, 0.1, 0.2], [0.3, 0.1, 0.1]]), np.array([[2.0, 1.0, 0.0], [0, 0, 0]])).tolist() == [1, 1]


def test_choice_stability_two_clusters_by_hand():
    # Cluster a favours candidate 0, cluster b candidate 1; on the full data they tie, so the first wins.
    values = np.array([[0.0, 1.0], [0.0, 1.0], [1.0, 0.0], [1.0, 0.0]])
    res = choice_stability(values, ["a", "a", "b", "b"], target=1, resamples=4000, seed=0)
    assert res["winner"] == 0
    assert res["gap"][0] == 0.0
    # Candidate 1 wins only when b is drawn twice: probability 1/4.
    assert res["share_target"] == pytest.approx(0.25, abs=0.03)
    assert res["share_target"] + res["share_winner"] == pytest.approx(1.0)
    assert res["gap"][1] == -1.0 and res["gap"][2] == 1.0


def test_choice_stability_a_clear_winner_is_always_chosen():
    values = np.column_stack([np.zeros(12), np.ones(12)])
    res = choice_stability(values, np.repeat(np.arange(6), 2), target=1, resamples=200, seed=1)
    assert res["winner"] == 0 and res["share_target"] == 0.0 and res["gap"] == [1.0, 1.0, 1.0]
