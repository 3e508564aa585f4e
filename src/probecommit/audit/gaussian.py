"""Audit rows from a belief without particles: a Gaussian (a Kalman or EKF filter) or a Gaussian mixture.

The audit reads, per episode, a *retained interval* and a *hull* in the decision coordinate
``z = c . theta`` (``c`` picks a latent or weighs several). For a particle belief they are the
top-weight prefix of mass ``nu`` and the particles' range. Without particles this module
defines them from the belief's marginal of ``z``, a one-dimensional Gaussian ``N(m, s^2)``
with ``m = c . mean`` and ``s^2 = c' cov c`` (a mixture: the mixture of its components'
marginals, with their weights):

* **retained interval** (``nu``): the *central* ``nu``-mass interval of the marginal,
  ``[F^-1((1 - nu)/2), F^-1((1 + nu)/2)]``; for one Gaussian ``m -+ Phi^-1((1 + nu)/2) s``.
  Coverage (truth inside it) then has the meaning it has for particles: a calibrated
  belief covers the truth in a fraction ``nu`` of episodes. (It is the marginal's interval,
  not the projection of the joint ``nu``-mass ellipsoid, which is wider and depends on the
  number of nuisance latents.)
* **hull**: ``[min_i (m_i - h s_i), max_i (m_i + h s_i)]`` over the components, ``h =
  hull_sigmas`` (4 by default). A Gaussian has no edge, so *support escape* here means the
  truth lies more than ``h`` marginal standard deviations beyond every component: the belief
  gave the region past the truth at most ``1 - Phi(h)`` of its mass (3.2e-5 at ``h = 4``),
  the analogue of a particle cloud that never reached it. Report ``h`` with the escape rate.
* **coverage score** ``score_s``: inside the hull, the smallest ``nu`` whose central interval
  holds the truth, ``|2 F(z_true) - 1|``; past it, ``1 + d / D`` (``d`` the distance past the
  hull, ``D`` the decision domain width), as for particles.
* ``post_var``: the marginal's variance; ``n_retained`` is not defined (left out).
"""

from __future__ import annotations

from statistics import NormalDist
from typing import Any, Sequence

import numpy as np

from probecommit.audit.rows import episode_row

_STD = NormalDist()
#: Default hull half-width in marginal standard deviations.
HULL_SIGMAS = 4.0


def _marginals(weights: Sequence[float], means: Any, covs: Any, decision: int | Sequence[float]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Component weights, marginal means and standard deviations of ``z = c . theta``."""
    w = np.asarray(weights, dtype=float).reshape(-1)
    mu = np.atleast_2d(np.asarray(means, dtype=float))
    cov = np.asarray(covs, dtype=float).reshape(mu.shape[0], mu.shape[1], mu.shape[1])
    if w.shape[0] != mu.shape[0]:
        raise ValueError(f"gaussian rows: {w.shape[0]} weights for {mu.shape[0]} components")
    c = np.zeros(mu.shape[1])
    if isinstance(decision, (int, np.integer)):
        c[int(decision)] = 1.0
    else:
        c = np.asarray(decision, dtype=float).reshape(-1)
        if c.shape[0] != mu.shape[1]:
            raise ValueError(f"gaussian rows: decision weights have {c.shape[0]} entries, the belief {mu.shape[1]} latents")
    if not (np.all(np.isfinite(w)) and np.all(w >= 0) and w.sum() > 0 and np.all(np.isfinite(mu)) and np.all(np.isfinite(cov))):
        raise ValueError("gaussian rows: weights, means and covariances must be finite, weights >= 0 with a positive sum")
    var = np.einsum("i,kij,j->k", c, cov, c)
    if np.any(var <= 0):
        raise ValueError(f"gaussian rows: the decision coordinate's variance must be > 0, got {var.tolist()}")
    return w / w.sum(), mu @ c, np.sqrt(var)


def _cdf(x: float, w: np.ndarray, m: np.ndarray, s: np.ndarray) -> float:
    return float(sum(wi * _STD.cdf((x - mi) / si) for wi, mi, si in zip(w, m, s)))


def _quantile(p: float, w: np.ndarray, m: np.ndarray, s: np.ndarray) -> float:
    """The mixture marginal's ``p``-quantile (bisection on its CDF; exact inverse for one component)."""
    if len(w) == 1:
        return float(m[0] + s[0] * _STD.inv_cdf(p))
    lo = float(np.min(m - 12 * s))
    hi = float(np.max(m + 12 * s))
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _cdf(mid, w, m, s) < p:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * max(1.0, abs(mid)):
            break
    return 0.5 * (lo + hi)


def belief_intervals(weights: Sequence[float], means: Any, covs: Any, *, decision: int | Sequence[float] = 0,
                     nu: float = 0.8, hull_sigmas: float = HULL_SIGMAS) -> dict[str, float]:
    """Retained interval, hull, marginal mean and variance of a Gaussian-mixture belief (module docstring).

    Returns:
        ``retained_lo``, ``retained_hi``, ``hull_lo``, ``hull_hi``, ``z_mean``, ``post_var``.
    """
    if not 0 < nu < 1:
        raise ValueError(f"gaussian rows: nu must be in (0, 1), got {nu!r}")
    if not hull_sigmas > 0:
        raise ValueError(f"gaussian rows: hull_sigmas must be > 0, got {hull_sigmas!r}")
    w, m, s = _marginals(weights, means, covs, decision)
    mean = float(w @ m)
    return {"retained_lo": _quantile((1 - nu) / 2, w, m, s), "retained_hi": _quantile((1 + nu) / 2, w, m, s),
            "hull_lo": float(np.min(m - hull_sigmas * s)), "hull_hi": float(np.max(m + hull_sigmas * s)),
            "z_mean": mean, "post_var": float(w @ (s**2 + m**2) - mean**2)}


def mixture_row(*, instance_id: str, k: int, z_true: float, action: Any, predicted: float, realized: float,
                weights: Sequence[float], means: Any, covs: Any, decision: int | Sequence[float] = 0, nu: float = 0.8,
                hull_sigmas: float = HULL_SIGMAS, domain_width: float | None = None, **labels: Any) -> dict[str, Any]:
    """One audit row from a Gaussian-mixture belief ``sum_i weights[i] N(means[i], covs[i])``.

    Args:
        instance_id, k, z_true, action, predicted, realized: As :func:`probecommit.audit.episode_row`.
        weights, means, covs: Components ``[K]``, ``[K, d]``, ``[K, d, d]``.
        decision: The decision coordinate: a latent's index, or weights ``c[d]`` of ``c . theta``.
        nu: Retained mass. hull_sigmas: Hull half-width in marginal standard deviations.
        domain_width: ``D``, for the coverage score past the hull.
        labels: ``repeat``, ``method``, ``variant`` and further columns, passed on.
    """
    found = belief_intervals(weights, means, covs, decision=decision, nu=nu, hull_sigmas=hull_sigmas)
    extra = {"post_var": found["post_var"], "hull_sigmas": float(hull_sigmas)}
    if domain_width is not None:
        z = float(z_true)
        if found["hull_lo"] <= z <= found["hull_hi"]:
            w, m, s = _marginals(weights, means, covs, decision)
            extra["score_s"] = min(abs(2 * _cdf(z, w, m, s) - 1), 1.0)
        else:
            extra["score_s"] = 1.0 + (max(found["hull_lo"] - z, 0.0) + max(z - found["hull_hi"], 0.0)) / float(domain_width)
    return episode_row(instance_id=instance_id, k=k, z_true=z_true, action=action, predicted=predicted,
                       realized=realized, retained=(found["retained_lo"], found["retained_hi"]),
                       hull=(found["hull_lo"], found["hull_hi"]), **labels, **extra)


def gaussian_row(*, mean: Any, cov: Any, **fields: Any) -> dict[str, Any]:
    """One audit row from a Gaussian belief ``N(mean[d], cov[d, d])`` (a Kalman/EKF filter's state);
    the other arguments are :func:`mixture_row`'s."""
    d = np.asarray(mean, dtype=float).reshape(-1).shape[0]
    return mixture_row(weights=[1.0], means=np.asarray(mean, dtype=float).reshape(1, d),
                       covs=np.asarray(cov, dtype=float).reshape(1, d, d), **fields)
