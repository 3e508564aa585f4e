"""Ground truth for the 1-D push: the closed form plus the simulator's own noise.

The paper's 1-D push has no scene ("closed form"); the simulator is the model's
``stop_distance`` evaluated at the truth, with Gaussian reading noise drawn from the
episode's generator. Queries are cached per ``(theta, impulse)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.tasks.base import CachedSimulator
from probecommit.tasks.push1d.model import stop_distance


class AnalyticPush1DSimulator(CachedSimulator):
    """Closed-form 1-D push with Gaussian reading noise.

    Args:
        noise_sigma: Noise added to each slide-distance reading (m).
    """

    engine = "analytic"

    def __init__(self, noise_sigma: float = 0.05) -> None:
        super().__init__()
        if not (np.isfinite(noise_sigma) and noise_sigma >= 0):
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
        self.noise_sigma = float(noise_sigma)

    def slide(self, mu: float, m: float, k_d: float, impulse: float) -> float:
        """Named query: slide distance (m) of an impulse (N s) from rest."""
        return float(stop_distance(impulse, mu, m, k_d))

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("slide", theta, (float(np.ravel(u)[0]),))
        return clean + self.noise_sigma * rng.standard_normal(1)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if context is None:
            raise ValueError("the push1d outcome needs the target distance (context)")
        stop = float(self.cached("slide", theta, (float(np.ravel(action)[0]),))[0])
        return {"realized": abs(stop - float(np.ravel(context)[0])), "stop": stop}
