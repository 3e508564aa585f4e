"""Random streams: one SeedSequence per (study, instance, repeat, purpose).

An episode's draws depend only on its own key, never on batch composition or the
number of workers, which is what makes runs bit-identical across backends.
"""

from __future__ import annotations

import zlib
from typing import Sequence

import numpy as np
from numpy.random.bit_generator import ISeedSequence

from probecommit.accel import production

ROLLOUT = 0  # probe choice and simulator noise
INFERENCE = 1  # prior particles, resampling offsets, jitter
STREAM_INSTANCES = 2**31 - 1
STREAM_BLIND = 2**31 - 2


def split_code(split: str) -> int:
    """Stable integer for a split name (crc32), used in spawn keys."""
    return zlib.crc32(split.encode())


def episode_rng(seed: int, split: str, instance_index: int, repeat: int, purpose: int) -> np.random.Generator:
    """The generator of one episode's stream: PCG64 seeded by ``SeedSequence(seed, spawn_key)``."""
    return episode_rngs(seed, split, [instance_index], [repeat], purpose)[0]


def episode_rngs(seed: int, split: str | Sequence[str], instance_indices: Sequence[int], repeats: Sequence[int],
                 purpose: int) -> list[np.random.Generator]:
    """:func:`episode_rng` of many episodes: the same generators, built faster.

    NumPy's ``SeedSequence`` hashes its entropy in Python-level steps (~30 us per episode);
    the compiled kernel hashes every episode's key in one call (the same words, tested against
    NumPy), and each PCG64 takes its state from them as it would from the SeedSequence.

    Args:
        split: The episodes' split, or one per episode.
    """
    splits = [split] * len(instance_indices) if isinstance(split, str) else list(split)
    codes = {name: split_code(name) for name in set(splits)}
    keys = [(codes[name], int(i), int(r), purpose) for name, i, r in zip(splits, instance_indices, repeats)]
    run_entropy = _uint32_words(seed) if isinstance(seed, (int, np.integer)) and seed >= 0 else None
    simple = run_entropy is not None and all(0 <= part <= 0xFFFFFFFF for key in keys for part in key)
    words = None
    if simple and keys:
        # Assembled entropy: the seed's words padded to the pool size (4), then the spawn key's.
        prefix = run_entropy + [0] * max(4 - len(run_entropy), 0)
        entropy = np.array([prefix + list(key) for key in keys], dtype=np.uint64)
        seed_words = production().seed_words
        if seed_words is not None:
            words = seed_words(entropy, 8)  # PCG64 asks for 4 uint64 = 8 uint32 words
    if words is None:
        return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(entropy=seed, spawn_key=key)))
                for key in keys]
    state = words.view("<u8")  # generate_state(4, uint64) is the uint32 words read little-endian
    return [np.random.Generator(np.random.PCG64(_StateWords(row))) for row in state]


def _uint32_words(value: int) -> list[int]:
    """An integer as little-endian 32-bit words (``[0]`` for zero), as SeedSequence splits it."""
    value = int(value)
    words = [value & 0xFFFFFFFF]
    value >>= 32
    while value:
        words.append(value & 0xFFFFFFFF)
        value >>= 32
    return words


class _StateWords(ISeedSequence):
    """A seed sequence whose generated state is already known (one episode's PCG64 words)."""

    __slots__ = ("_words",)

    def __init__(self, words: np.ndarray) -> None:
        self._words = words

    def generate_state(self, n_words: int, dtype=np.uint32) -> np.ndarray:
        if n_words != 4 or np.dtype(dtype) != np.uint64:  # PCG64 asks for exactly this
            raise ValueError("this seed sequence holds PCG64's four uint64 state words only")
        return self._words.copy()


def instance_rng(seed: int, split: str) -> np.random.Generator:
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(STREAM_INSTANCES, split_code(split)))
    return np.random.Generator(np.random.PCG64(ss))


def blind_rng(seed: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(entropy=seed, spawn_key=(STREAM_BLIND,))))
