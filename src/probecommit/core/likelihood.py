"""Observation likelihoods for the particle filter.

Each maps an observation ``y[E, m]`` and predictions ``pred[E, N, m]`` to
log-likelihoods ``[E, N]``. Constants that do not depend on the particle are kept
so that the prequential surprise (a predictive density) is a true density.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


class Likelihood(Protocol):
    def log_likelihood(self, y: np.ndarray, pred: np.ndarray) -> np.ndarray: ...


def _check_sigma(sigma: float) -> float:
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma <= 0:
        raise ValueError(f"likelihood sigma must be a positive finite number, got {sigma!r}")
    return sigma


@dataclass(frozen=True)
class GaussianLikelihood:
    """Isotropic Gaussian ``N(y; f(u, theta), sigma^2 I)``."""

    sigma: float
    #: Built from + - * / only, so a value depends on its own prediction alone, computed anywhere
    #: (an array of two levels or of every particle) to the same bits.
    arithmetic = True

    def __post_init__(self) -> None:
        _check_sigma(self.sigma)

    def log_likelihood(self, y: np.ndarray, pred: np.ndarray) -> np.ndarray:
        # The textbook expression -0.5 * sum(((y - f) / sigma)^2) - m log(sigma sqrt(2 pi)), evaluated
        # in one [E, N, m] buffer: the same operations in the same order, so the same bits.
        resid = np.subtract(y[:, None, :], pred, dtype=float)
        resid /= self.sigma
        squares = np.multiply(resid, resid, out=resid)
        m = pred.shape[-1]
        # A sum over one squared residual is that square (0.0 + x == x for x >= +0 and NaN).
        total = squares[..., 0] if m == 1 else np.sum(squares, axis=-1)
        total *= -0.5
        total -= m * np.log(self.sigma * np.sqrt(2 * np.pi))
        return total


@dataclass(frozen=True)
class TemperedLikelihood:
    """Power likelihood ``p^(1/T)``; ``T = 4`` doubles the effective sigma."""

    base: Likelihood
    temperature: float

    def __post_init__(self) -> None:
        if not self.temperature >= 1:
            raise ValueError(f"temperature must be >= 1, got {self.temperature!r}")

    @property
    def arithmetic(self) -> bool:
        """A division of the base's value: arithmetic when the base is."""
        return bool(getattr(self.base, "arithmetic", False))

    def log_likelihood(self, y: np.ndarray, pred: np.ndarray) -> np.ndarray:
        return self.base.log_likelihood(y, pred) / self.temperature


@dataclass(frozen=True)
class MixtureLikelihood:
    """Contamination mixture ``(1 - eps) p + eps q0`` with ``q0`` uniform on ``[low, high]^m``."""

    base: Likelihood
    epsilon: float
    low: float
    high: float

    def __post_init__(self) -> None:
        if not 0 <= self.epsilon < 1:
            raise ValueError(f"mixture epsilon must be in [0, 1), got {self.epsilon!r}")
        if not self.high > self.low:
            raise ValueError("mixture range must have high > low")

    def log_likelihood(self, y: np.ndarray, pred: np.ndarray) -> np.ndarray:
        base = self.base.log_likelihood(y, pred)
        m = pred.shape[-1]
        inside = np.all((y >= self.low) & (y <= self.high), axis=-1)  # [E]
        log_q0 = np.where(inside, -m * np.log(self.high - self.low), -np.inf)[:, None]
        if self.epsilon == 0:
            return base
        return np.logaddexp(np.log1p(-self.epsilon) + base, np.log(self.epsilon) + log_q0)
