"""Hinge ground truth in closed form (the model at the truth plus reading noise): for tests and quick runs."""

from __future__ import annotations

from probecommit.tasks.base import TargetMissSimulator
from probecommit.tasks.hinge.model import stop_angle


class AnalyticHingeSimulator(TargetMissSimulator):
    """Closed-form coast with Gaussian reading noise.

    Args:
        noise_sigma: Noise added to each stop-angle reading (rad).
    """

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators
    family = "hinge"
    query, outcome, target = "coast", "angle", "target angle"

    def __init__(self, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)

    def coast(self, f: float, b: float, m: float, speed: float) -> float:
        """Named query: stop angle (rad) after release at ``speed`` rad/s."""
        return float(stop_angle(speed, f, b, m))
