"""Ground truth for planar slide: the closed-form model plus the simulator's own noise."""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.tasks.base import NoisySimulator
from probecommit.tasks.planar_slide.model import rest_position


class AnalyticPlanarSlideSimulator(NoisySimulator):
    """Closed-form planar slide with Gaussian reading noise.

    Args:
        noise_sigma: Noise per rest-position component added to each probe reading (m).
    """

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators

    def __init__(self, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)

    def rest(self, mu: float, phi: float, m: float, jx: float, jy: float) -> np.ndarray:
        """Named query: rest position of a strike ``(jx, jy)``."""
        return rest_position(np.array([jx, jy]), np.float64(mu), np.float64(phi), np.float64(m))

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("rest", theta, (float(np.ravel(u)[0]), 0.0))
        return clean + self.noise_sigma * rng.standard_normal(2)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        rest = self.cached("rest", theta, np.ravel(action))
        return {"realized": float(np.linalg.norm(rest - np.asarray(context, dtype=float)))}
