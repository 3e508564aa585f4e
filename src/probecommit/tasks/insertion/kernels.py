"""Insertion's compiled reweighting (``probecommit.accel``'s JIT): the tap's pocket test is the
family's own formula, so its kernel lives with the family. One pass picks each particle's level
log-likelihood; the same IEEE operations as ``InsertionModel.add_reading_log_likelihood``'s NumPy
path, in the same order (``tests/tasks/insertion/test_model.py`` checks the two).
"""

from __future__ import annotations

import numpy as np

from probecommit.accel.compiled import kernel


@kernel("f8[:, ::1](f8[::1], f8[:, :, ::1], f8[:, ::1], f8[:, ::1], f8)")
def _slot_tap_log_weights(u, particles, log_weights, level_ll, offset):  # pragma: no cover - compiled
    n_e, n = log_weights.shape
    out = np.empty((n_e, n))
    for e in range(n_e):
        in_pocket, on_top = level_ll[e, 0], level_ll[e, 1]
        for i in range(n):
            # |u - x| < (0.6 c + 4) + offset: insertion's reads_pocket, the same IEEE operations in order
            distance = abs(u[e] - particles[e, i, 0])
            boundary = 0.6 * particles[e, i, 1]
            boundary += 4.0
            boundary += offset
            out[e, i] = log_weights[e, i] + (in_pocket if distance < boundary else on_top)
    return out


def slot_tap_log_weights(u: np.ndarray, particles: np.ndarray, log_weights: np.ndarray, level_ll: np.ndarray,
                         offset: float) -> np.ndarray:
    """Insertion's reweighting in one pass (see ``InsertionModel.add_reading_log_likelihood``):
    ``log_weights + (level_ll[:, 0] if the tap at u reads the pocket else level_ll[:, 1])``."""
    f64 = np.float64
    return _slot_tap_log_weights(np.ascontiguousarray(u, dtype=f64).reshape(-1), np.ascontiguousarray(particles, dtype=f64),
                                 np.ascontiguousarray(log_weights, dtype=f64), np.ascontiguousarray(level_ll, dtype=f64),
                                 float(offset))
