"""Audit rows from a robot's own belief: for robots that do not use :class:`probecommit.Session`.

A robot with its own particle filter gives, per committed episode, its particles'
decision coordinate, their weights, the committed action and its score, and (after a
measurement) the true decision coordinate and the realized outcome;
:func:`episode_row` returns the row the audit reads (``store.schema.EPISODE_COLUMNS``),
with the retained set built exactly as the executor builds it (top-weight prefix of
mass ``nu``).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from probecommit.core.retained import coverage_score, masked_interval, retained_mask, weighted_variance


def episode_row(*, instance_id: str, k: int, z_true: float, action: float | Sequence[float], predicted: float,
                realized: float, z_particles: Sequence[float] | None = None, weights: Sequence[float] | None = None,
                nu: float = 0.8, retained: tuple[float, float] | None = None, hull: tuple[float, float] | None = None,
                domain_width: float | None = None, repeat: int = 0, method: str = "probe_robust",
                variant: str = "deployed", **extra: Any) -> dict[str, Any]:
    """One audit row.

    Give either the belief (``z_particles`` and ``weights``; the retained set and hull
    are computed from them, and so are ``post_var``, ``n_retained`` and, with
    ``domain_width``, the coverage score ``score_s``) or the intervals themselves
    (``retained`` and ``hull``).

    Args:
        instance_id: The cluster: a block position, a truth.
        k: Probes before the commit.
        z_true: True decision coordinate (e.g. the measured hole centre).
        action: Committed action (scalar or vector).
        predicted: The executor's score of that action (failure fraction or max miss).
        realized: Realized failure (0/1) or miss.
        z_particles: Decision coordinate of each particle ``[N]``.
        weights: Their weights ``[N]`` (normalized here).
        nu: Retained mass.
        retained, hull: Intervals, when no particles are given.
        domain_width: ``D`` for the coverage score past the hull.
        repeat: Repeat index within ``(instance_id, k)``.
        method, variant: Labels.
        extra: Further columns kept as given (``entered``, ``aim_error``, ...).

    Raises:
        ValueError: missing or non-finite inputs, naming them.
    """
    for name, value in (("z_true", z_true), ("predicted", predicted), ("realized", realized)):
        if not np.isfinite(float(value)):
            raise ValueError(f"episode_row: {name} must be finite, got {value!r}")
    row: dict[str, Any] = {"instance_id": str(instance_id), "repeat": int(repeat), "k": int(k), "method": method,
                           "variant": variant, "predicted": float(predicted), "realized": float(realized),
                           "z_true": float(z_true)}
    a = np.atleast_1d(np.asarray(action, dtype=float))
    if a.size == 1:
        row["action"] = float(a[0])
    else:
        row.update({f"action_{i}": float(v) for i, v in enumerate(a)})
    if z_particles is not None:
        if weights is None:
            raise ValueError("episode_row: z_particles given without weights")
        z = np.asarray(z_particles, dtype=float).reshape(1, -1)
        w = np.asarray(weights, dtype=float).reshape(1, -1)
        if z.shape != w.shape or z.size == 0:
            raise ValueError(f"episode_row: {z.shape[1]} particles but {w.shape[1]} weights")
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(w)) and np.all(w >= 0) and w.sum() > 0):
            raise ValueError("episode_row: particles and weights must be finite, weights >= 0 with a positive sum")
        w = w / w.sum()
        mask = retained_mask(w, nu)
        lo, hi = masked_interval(z, mask)
        all_mask = np.ones_like(mask)
        hlo, hhi = masked_interval(z, all_mask)
        row.update(retained_lo=float(lo[0]), retained_hi=float(hi[0]), hull_lo=float(hlo[0]), hull_hi=float(hhi[0]),
                   post_var=float(weighted_variance(z, w)[0]), n_retained=int(mask.sum()))
        if domain_width is not None:
            row["score_s"] = float(coverage_score(z, w, np.array([float(z_true)]), domain_width)[0])
    else:
        if retained is None or hull is None:
            raise ValueError("episode_row: give z_particles and weights, or both retained and hull intervals")
        row.update(retained_lo=float(retained[0]), retained_hi=float(retained[1]), hull_lo=float(hull[0]),
                   hull_hi=float(hull[1]))
    # The episode-row rules at write time too (audit.io.validate_episodes applies them on every read).
    for name in ("predicted", "realized"):
        if row[name] < 0:
            raise ValueError(f"episode_row: {name} is a loss and cannot be negative, got {row[name]!r}")
    for lo, hi in (("retained_lo", "retained_hi"), ("hull_lo", "hull_hi")):
        if not (np.isfinite(row[lo]) and np.isfinite(row[hi]) and row[lo] <= row[hi]):
            raise ValueError(f"episode_row: {lo} {row[lo]!r} must be finite and <= {hi} {row[hi]!r}")
    row["covered"] = bool(row["retained_lo"] <= row["z_true"] <= row["retained_hi"])
    row["escaped"] = bool(not row["hull_lo"] <= row["z_true"] <= row["hull_hi"])
    row.update(extra)
    return row
