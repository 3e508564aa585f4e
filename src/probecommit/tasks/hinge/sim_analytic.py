"""Hinge ground truth in closed form (the model at the truth plus reading noise): for tests and quick runs."""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.tasks.base import CachedSimulator
from probecommit.tasks.hinge.model import stop_angle


class AnalyticHingeSimulator(CachedSimulator):
    """Closed-form coast with Gaussian reading noise.

    Args:
        noise_sigma: Noise added to each stop-angle reading (rad).
    """

    engine = "analytic"

    def __init__(self, noise_sigma: float = 0.02) -> None:
        super().__init__()
        if not (np.isfinite(noise_sigma) and noise_sigma >= 0):
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
        self.noise_sigma = float(noise_sigma)

    def coast(self, f: float, b: float, m: float, speed: float) -> float:
        """Named query: stop angle (rad) after release at ``speed`` rad/s."""
        return float(stop_angle(speed, f, b, m))

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("coast", theta, (float(np.ravel(u)[0]),))
        return clean + self.noise_sigma * rng.standard_normal(1)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if context is None:
            raise ValueError("the hinge outcome needs the target angle (context)")
        angle = float(self.cached("coast", theta, (float(np.ravel(action)[0]),))[0])
        return {"realized": abs(angle - float(np.ravel(context)[0])), "angle": angle}
