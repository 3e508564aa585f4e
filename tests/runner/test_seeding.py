"""Episode streams: the batched generators are NumPy's SeedSequence-seeded PCG64, bit for bit."""

import numpy as np
import pytest

from probecommit.runner import seeding
from probecommit.runner.seeding import INFERENCE, ROLLOUT, episode_rng, episode_rngs, split_code


def numpy_stream(seed, split, index, repeat, purpose):
    spawn_key = (split_code(split), int(index), int(repeat), purpose)
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(entropy=seed, spawn_key=spawn_key)))


@pytest.mark.parametrize("seed", [0, 1, 7, 2**32 - 1, 2**32, 2**40 + 5, 2**63 - 1, 2**100 + 3])
def test_batched_streams_equal_numpy_seed_sequences(seed):
    rng = np.random.default_rng(seed % 2**32)
    # Small indices and indices up to 2**32 + 5 (two words: NumPy's own SeedSequence takes those).
    indices = np.concatenate([rng.integers(0, 1000, 12), rng.integers(0, 2**32 + 5, 12, dtype=np.int64)])
    repeats = rng.integers(0, 40, indices.size)
    for purpose in (ROLLOUT, INFERENCE):
        fast = episode_rngs(seed, "val", indices, repeats, purpose)
        for gen, i, r in zip(fast, indices, repeats):
            ref = numpy_stream(seed, "val", i, r, purpose)
            assert gen.bit_generator.state == ref.bit_generator.state
            assert np.array_equal(gen.standard_normal(5), ref.standard_normal(5))


def test_one_stream_is_the_batched_one():
    assert episode_rng(3, "test", 17, 2, ROLLOUT).random(4).tolist() == episode_rngs(3, "test", [17], [2], ROLLOUT)[0].random(4).tolist()
    assert episode_rngs(3, "test", [], [], ROLLOUT) == []


def test_without_the_compiled_kernel_numpy_seeds_each_stream(monkeypatch):
    monkeypatch.setenv("PROBECOMMIT_KERNELS", "numpy")  # the reference path: NumPy's SeedSequence per stream
    got = episode_rngs(5, "b", [1, 2], [0, 3], INFERENCE)
    assert [g.bit_generator.state for g in got] == [numpy_stream(5, "b", 1, 0, INFERENCE).bit_generator.state,
                                                     numpy_stream(5, "b", 2, 3, INFERENCE).bit_generator.state]


def test_a_negative_seed_fails_as_numpy_does():
    with pytest.raises(ValueError):
        episode_rngs(-1, "b", [1], [0], ROLLOUT)


def test_state_words_serve_pcg64_only():
    words = seeding._StateWords(np.arange(4, dtype=np.uint64))
    with pytest.raises(ValueError, match="PCG64"):
        words.generate_state(8, np.uint32)


def test_a_split_per_episode_gives_each_its_own_stream():
    splits, indices, repeats = ["val", "test", "val"], [4, 4, 9], [0, 1, 2]
    got = episode_rngs(8, splits, indices, repeats, ROLLOUT)
    assert [g.bit_generator.state for g in got] == [numpy_stream(8, s, i, r, ROLLOUT).bit_generator.state
                                                     for s, i, r in zip(splits, indices, repeats)]
