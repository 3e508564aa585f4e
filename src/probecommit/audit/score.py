"""The episode coverage score ``s`` (paper Sec. IV, "The episode score").

Sort particles by descending weight (ties in index order), let ``W_m`` be the
cumulative mass of the first ``m`` and ``I_m`` the range of the decision coordinate
over them. The score is the mass of the shortest prefix covering the truth,
``s = min{W_m : z* in I_m}``, so ``s <= t`` implies ``z*`` lies in the retained
interval at threshold ``t``. When the truth escapes the full hull the score
continues past one: ``s = 1 + d(z*, hull) / D``.
"""

from __future__ import annotations

import numpy as np

from probecommit.core.retained import prefix_mass


def coverage_score(z: np.ndarray, weights: np.ndarray, z_true: np.ndarray, domain_width: float) -> np.ndarray:
    """Coverage score per episode.

    Args:
        z: Decision coordinate of every particle ``[E, N]``.
        weights: Normalized weights ``[E, N]``.
        z_true: True decision coordinate ``[E]``.
        domain_width: ``D``, the decision domain width that scales distance past the hull.

    Returns:
        ``[E]`` scores; ``<= 1`` when the truth is inside the hull (clipped at 1
        against round-off), ``1 + d / D`` exactly when it escapes.
    """
    z = np.asarray(z, dtype=float)
    z_true = np.asarray(z_true, dtype=float)
    order, cum = prefix_mass(np.asarray(weights, dtype=float))
    z_sorted = np.take_along_axis(z, order, axis=-1)
    run_lo = np.minimum.accumulate(z_sorted, axis=-1)
    run_hi = np.maximum.accumulate(z_sorted, axis=-1)
    covers = (run_lo <= z_true[:, None]) & (z_true[:, None] <= run_hi)
    first = np.argmax(covers, axis=-1)
    inside = covers.any(axis=-1)
    # A float cumulative sum of normalized weights can overshoot 1 by an ulp
    # (0.44697 + 0.29545 + 0.25758 -> 1.0000000000000002); clip so that s > 1
    # means escape and nothing else. This never changes which prefix covers.
    s_inside = np.minimum(np.take_along_axis(cum, first[:, None], axis=-1)[:, 0], 1.0)
    hull_lo, hull_hi = run_lo[:, -1], run_hi[:, -1]
    distance = np.maximum(hull_lo - z_true, 0.0) + np.maximum(z_true - hull_hi, 0.0)
    return np.where(inside, s_inside, 1.0 + distance / float(domain_width))
