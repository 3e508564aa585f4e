"""Compiled SeedSequence hashing for the episodes' random streams (``runner.seeding``).

NumPy's ``SeedSequence`` hashes its entropy in Python-level steps (~30 us per episode); this
kernel hashes every episode's key in one call. Integer arithmetic: the words are NumPy's
exactly (tested), so the random streams do not depend on the path.
"""

from __future__ import annotations

import numpy as np

from probecommit.accel.compiled import kernel

_MASK32 = np.uint64(0xFFFFFFFF)
_SHIFT16 = np.uint64(16)


@kernel("u4[:, ::1](u8[:, ::1], i8)")
def _seed_sequence_words(entropy, n_words):  # pragma: no cover - compiled
    """``SeedSequence`` (pool size 4) of each row of assembled entropy words, then
    ``generate_state(n_words, uint32)``: O'Neill's seed_seq hash, in uint64 arithmetic
    masked to 32 bits after every operation."""
    n_keys, n_entropy = entropy.shape
    out = np.empty((n_keys, n_words), dtype=np.uint32)
    mixer = np.empty(4, dtype=np.uint64)
    for key in range(n_keys):
        hash_const = np.uint64(0x43B0D7E5)  # INIT_A
        for i in range(4):
            value = entropy[key, i] if i < n_entropy else np.uint64(0)
            value = (value ^ hash_const) & _MASK32
            hash_const = (hash_const * np.uint64(0x931E8875)) & _MASK32  # MULT_A
            value = (value * hash_const) & _MASK32
            mixer[i] = value ^ (value >> _SHIFT16)
        for i_src in range(n_entropy if n_entropy > 4 else 4):
            for i_dst in range(4):
                if i_src < 4 and i_src == i_dst:
                    continue
                value = mixer[i_src] if i_src < 4 else entropy[key, i_src]
                value = (value ^ hash_const) & _MASK32
                hash_const = (hash_const * np.uint64(0x931E8875)) & _MASK32
                value = (value * hash_const) & _MASK32
                value = value ^ (value >> _SHIFT16)
                # mix(x, y) = x * MIX_MULT_L - y * MIX_MULT_R, then xor-shift
                result = ((mixer[i_dst] * np.uint64(0xCA01F9DD)) - (value * np.uint64(0x4973F715))) & _MASK32
                mixer[i_dst] = result ^ (result >> _SHIFT16)
        hash_const = np.uint64(0x8B51F9DD)  # INIT_B
        for i in range(n_words):
            value = (mixer[i % 4] ^ hash_const) & _MASK32
            hash_const = (hash_const * np.uint64(0x58F38DED)) & _MASK32  # MULT_B
            value = (value * hash_const) & _MASK32
            out[key, i] = np.uint32(value ^ (value >> _SHIFT16))
    return out


def seed_sequence_words(entropy: np.ndarray, n_words: int) -> np.ndarray:
    """The state words ``[K, n_words]`` (uint32) that ``numpy.random.SeedSequence`` (pool
    size 4) generates from each row of assembled entropy words ``[K, L]``."""
    return _seed_sequence_words(np.ascontiguousarray(entropy, dtype=np.uint64), int(n_words))
