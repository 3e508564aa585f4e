"""Ground truth for the 1-D push: the closed form plus the simulator's own noise.

The paper's 1-D push has no scene ("closed form"); the simulator is the model's
``stop_distance`` evaluated at the truth, with Gaussian reading noise drawn from the
episode's generator. Queries are cached per ``(theta, impulse)``.
"""

from __future__ import annotations

from probecommit.tasks.base import TargetMissSimulator
from probecommit.tasks.push1d.model import stop_distance


class AnalyticPush1DSimulator(TargetMissSimulator):
    """Closed-form 1-D push with Gaussian reading noise.

    Args:
        noise_sigma: Noise added to each slide-distance reading (m).
    """

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators
    family = "push1d"
    query, outcome, target = "slide", "stop", "target distance"

    def __init__(self, noise_sigma: float = 0.05) -> None:
        super().__init__(noise_sigma)

    def slide(self, mu: float, m: float, k_d: float, impulse: float) -> float:
        """Named query: slide distance (m) of an impulse (N s) from rest."""
        return float(stop_distance(impulse, mu, m, k_d))
