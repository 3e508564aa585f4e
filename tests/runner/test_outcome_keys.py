"""Realized outcomes are remembered per (run, instance, action): instance indices restart at 0 in every run, so a
batch pooling runs of several splits holds several instances under one index (a re-split pool: Split B's
calibration and test runs). Each episode must get its own instance's answer, in any order and through subsets
sharing the memo, as margin searches and threaded commits do."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.runner.inference import ProbeBatch, _execute, outcome_keys


class _Engine:
    """Answers ``execute`` from the truth and the action alone; counts its calls."""

    parallel_queries = False

    def __init__(self) -> None:
        self.calls = 0

    def execute(self, theta, action, context=None):
        self.calls += 1
        return {"realized": float(theta[0] * 1000.0 + action[0])}


def _pool(sizes: list[int], repeats: int, pooled: bool) -> ProbeBatch:
    """Runs ``s0, s1, ..`` of ``sizes`` instances each (indices from 0 in every run), ``repeats`` episodes each."""
    split, ids, index, truths = [], [], [], []
    for r, n in enumerate(sizes):
        for i in range(n):
            for _ in range(repeats):
                split.append(f"s{r}")
                ids.append(f"s{r}-{i:04d}")
                index.append(i)
                truths.append([r * 100.0 + i])
    e = len(ids)
    return ProbeBatch(np.array(split, dtype=object) if pooled else "s0", np.array(ids, dtype=object),
                      np.array(index), np.zeros(e, int), np.array(truths), np.zeros((e, 1, 1)), np.zeros((e, 1, 1)))


@settings(max_examples=40, deadline=None)
@given(sizes=st.lists(st.integers(1, 5), min_size=2, max_size=3), repeats=st.integers(1, 3),
       n_actions=st.integers(2, 6), seed=st.integers(0, 2**16))
def test_every_episode_of_a_pool_gets_its_own_instances_outcome(sizes, repeats, n_actions, seed):
    batch = _pool(sizes, repeats, pooled=True)
    rng = np.random.default_rng(seed)
    grid = np.arange(n_actions, dtype=float)[:, None]
    memo: dict = {}
    engine = _Engine()
    for _ in range(2):  # two commits sharing the memo: the second in a shuffled subset, as a margin search asks
        rows = rng.permutation(batch.n_episodes)[: max(1, batch.n_episodes // 2)]
        part = batch.subset(rows)
        index = rng.integers(n_actions, size=len(rows))
        realized, status, _ = _execute(engine, part, grid[index], index, n_actions, memo)
        assert (status == "ok").all()
        np.testing.assert_array_equal(realized, part.truths[:, 0] * 1000.0 + index)
    distinct = {(s, i) for s, i in zip(batch.split, batch.instance_index)}
    assert len(distinct) == sum(sizes)  # the pool's indices do repeat across its runs
    assert engine.calls == len(memo)  # one call per distinct (run, instance, action)


def test_a_single_runs_keys_are_its_instance_and_action():
    batch = _pool([3], 2, pooled=False)
    first, inverse, keys = outcome_keys(batch, np.arange(6), np.array([1, 1, 0, 1, 2, 2]), 4)
    assert keys == [("s0", 1), ("s0", 4), ("s0", 5), ("s0", 10)]
    np.testing.assert_array_equal(inverse, [0, 0, 1, 2, 3, 3])
    np.testing.assert_array_equal(first, [0, 2, 3, 4])


@settings(max_examples=30, deadline=None)
@given(sizes=st.lists(st.integers(1, 4), min_size=1, max_size=3), n_actions=st.integers(2, 5), seed=st.integers(0, 2**16))
def test_keys_of_a_batch_naming_one_split_per_episode_are_those_of_its_name(sizes, n_actions, seed):
    """A batch naming its split per episode, every one the same (a run's), gets the keys, ``first`` and
    ``inverse`` of the same batch naming it once; a pool of several splits, those of factorizing them."""
    import pandas as pd

    pooled = _pool(sizes, 2, pooled=True)
    rng = np.random.default_rng(seed)
    rows = rng.permutation(pooled.n_episodes)[: max(1, pooled.n_episodes // 2)]
    index = rng.integers(n_actions, size=len(rows))
    got = outcome_keys(pooled, rows, index, n_actions)
    flat = pooled.instance_index[rows].astype(np.int64) * n_actions + index
    codes, names = pd.factorize(np.asarray(pooled.split, dtype=object)[rows])
    _, first, inverse = np.unique(flat * len(names) + codes, return_index=True, return_inverse=True)
    assert got[2] == [(str(names[c]), f) for c, f in zip(codes[first].tolist(), flat[first].tolist())]
    np.testing.assert_array_equal(got[0], first)
    np.testing.assert_array_equal(got[1], inverse)
    if len(sizes) == 1:
        once = _pool(sizes, 2, pooled=False)
        same = outcome_keys(once, rows, index, n_actions)
        assert same[2] == got[2]
        np.testing.assert_array_equal(same[0], got[0])
        np.testing.assert_array_equal(same[1], got[1])
