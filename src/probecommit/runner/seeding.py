"""Random streams: one SeedSequence per (study, instance, repeat, purpose).

An episode's draws depend only on its own key, never on batch composition or the
number of workers, which is what makes runs bit-identical across backends.
"""

from __future__ import annotations

import zlib

import numpy as np

ROLLOUT = 0  # probe choice and simulator noise
INFERENCE = 1  # prior particles, resampling offsets, jitter
STREAM_INSTANCES = 2**31 - 1
STREAM_BLIND = 2**31 - 2


def split_code(split: str) -> int:
    """Stable integer for a split name (crc32), used in spawn keys."""
    return zlib.crc32(split.encode())


def episode_rng(seed: int, split: str, instance_index: int, repeat: int, purpose: int) -> np.random.Generator:
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(split_code(split), instance_index, repeat, purpose))
    return np.random.Generator(np.random.PCG64(ss))


def instance_rng(seed: int, split: str) -> np.random.Generator:
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(STREAM_INSTANCES, split_code(split)))
    return np.random.Generator(np.random.PCG64(ss))


def blind_rng(seed: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(entropy=seed, spawn_key=(STREAM_BLIND,))))
