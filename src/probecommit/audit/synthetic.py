"""Synthetic episode tables for tests and benchmarks (no task model, no engine).

Beliefs are real particle clouds in the decision coordinate: the retained
interval, hull, coverage score and posterior variance are computed with the core
functions exactly as the runner does, so the audit sees internally consistent
tables. Outcomes are Bernoulli draws whose rate exceeds the claimed score when
the belief is off target, which makes the executor optimistic in a controlled way.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from probecommit.audit.score import coverage_score
from probecommit.core.retained import masked_interval, retained_mask, weighted_variance


def synthetic_episodes(n_instances: int = 96, n_repeats: int = 4, budgets: Sequence[int] = tuple(range(1, 9)), *,
                       n_particles: int = 256, seed: int = 0, bias: float = 1.0, domain_width: float = 20.0,
                       method: str = "probe_robust", variant: str = "deployed", prefix: str = "inst") -> pd.DataFrame:
    """An episode table with the schema's columns.

    Args:
        n_instances: Instances (clusters).
        n_repeats: Repeats per instance.
        budgets: Budgets per trajectory.
        n_particles: Particles per belief.
        seed: Seed of all draws.
        bias: Scale of the per-instance belief bias (0 gives well-calibrated beliefs).
        domain_width: ``D`` for the score past the hull.
        method, variant: Labels.
        prefix: Instance id prefix.

    Returns:
        ``n_instances * n_repeats * len(budgets)`` episodes.
    """
    rng = np.random.default_rng(seed)
    budgets = np.asarray(sorted(budgets), dtype=int)
    m, r, kk = n_instances, n_repeats, budgets.size
    z_true = rng.uniform(-10, 10, m)
    inst_bias = bias * rng.normal(0, 1.0, m)
    shape = (m, r, kk)
    spread = 3.0 / budgets[None, None, :] ** 0.8 * np.ones(shape)
    # The bias grows with the budget: evidence pulls a misspecified belief
    # confidently onto the wrong place, as in the paper's boundary error.
    drift = inst_bias[:, None, None] * (0.5 + 0.15 * budgets)[None, None, :]
    mu = z_true[:, None, None] + drift + 0.5 * spread * rng.normal(size=shape)
    e = m * r * kk
    z = mu.reshape(e, 1) + spread.reshape(e, 1) * rng.normal(size=(e, n_particles))
    logw = -0.5 * rng.exponential(1.0, size=(e, n_particles))
    w = np.exp(logw)
    w[rng.random((e, n_particles)) < 0.02] = 0.0  # some dead particles, as after a hard likelihood
    w /= w.sum(axis=1, keepdims=True)
    zt = np.repeat(z_true, r * kk)
    mask = retained_mask(w, 0.8)
    rlo, rhi = masked_interval(z, mask)
    hlo, hhi = z.min(axis=1), z.max(axis=1)
    s = coverage_score(z, w, zt, domain_width)
    post_var = weighted_variance(z, w)
    off = np.abs(mu.reshape(e) - zt) / spread.reshape(e)
    predicted = np.clip(0.35 * spread.reshape(e) / 3.0 * rng.random(e), 0, 1)
    p_fail = np.clip(predicted + 0.05 + 0.15 * off, 0, 1)
    realized = (rng.random(e) < p_fail).astype(float)
    escaped = (zt < hlo) | (zt > hhi)
    surprise = 1.0 + rng.exponential(1.0, e) + 2.0 * escaped * rng.random(e)
    ii, rr, kk_idx = np.meshgrid(np.arange(m), np.arange(r), np.arange(kk), indexing="ij")
    return pd.DataFrame({
        "instance_id": np.array([f"{prefix}{i:04d}" for i in range(m)])[ii.ravel()],
        "repeat": rr.ravel().astype(np.int64),
        "k": budgets[kk_idx.ravel()].astype(np.int64),
        "method": method,
        "variant": variant,
        "action": np.round(mu.reshape(e) * 2) / 2,
        "predicted": predicted,
        "realized": realized,
        "z_true": zt,
        "retained_lo": rlo,
        "retained_hi": rhi,
        "hull_lo": hlo,
        "hull_hi": hhi,
        "covered": (rlo <= zt) & (zt <= rhi),
        "escaped": escaped,
        "score_s": s,
        "post_var": post_var,
        "max_surprise": surprise,
        "n_retained": mask.sum(axis=1).astype(np.int64),
        "status": "ok",
        "error": "",
    })
