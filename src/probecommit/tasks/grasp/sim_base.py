"""Grasp ground truth: squeeze and lift queries, cached; the crush rule; the force-balance simulator.

A simulator answers two deterministic named queries: ``squeeze(mu, m, u)`` (slip in mm
of a 50 ms relaxation to force ``u``) and ``lift(mu, m, F)`` (slip in mm of the object
relative to the pads during the commit's lift). The commit succeeds when the lift
holds (slip below ``HOLD_SLIP_MM``) and the grip does not exceed the crush limit,
``1.5 F_lift`` of the truth's force balance: no engine models fracture, so the crush
limit is a rule of the task, applied the same way for every engine.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.tasks.base import NoisySimulator
from probecommit.tasks.grasp.model import CRUSH_RATIO, LIFT_ACCEL, hold_force, squeeze_slip_mm

#: The lift held if the object slid less than this relative to the pads (mm).
HOLD_SLIP_MM = 2.0


class GraspSimulator(NoisySimulator):
    """Base class: cached queries, reading noise, and the success rule.

    Args:
        noise_sigma: Noise added to each slip reading (mm).
    """

    engine = "abstract"

    def __init__(self, noise_sigma: float = 2.0) -> None:
        super().__init__(noise_sigma)

    def squeeze(self, mu: float, m: float, u: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def lift(self, mu: float, m: float, force: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("squeeze", theta, (float(np.ravel(u)[0]),))
        return clean + self.noise_sigma * rng.standard_normal(1)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        force = float(np.ravel(action)[0])
        slip = float(self.cached("lift", theta, (force,))[0])
        if not np.isfinite(slip):
            raise FloatingPointError(f"{self.engine} lift returned {slip} at grip {force} N")
        held = slip < HOLD_SLIP_MM
        crushed = force >= CRUSH_RATIO * float(hold_force(theta[0], theta[1], LIFT_ACCEL))
        return {"realized": float(not (held and not crushed)), "held": held, "crushed": crushed, "slip_mm": slip}

    def feasible(self, theta: np.ndarray, forces: np.ndarray) -> bool:
        """Whether some grip on ``forces`` succeeds for this truth (only forces near its window are tried)."""
        f_lift = float(hold_force(theta[0], theta[1], LIFT_ACCEL))
        near = [f for f in np.ravel(forces) if 0.8 * f_lift < f < CRUSH_RATIO * f_lift]
        return any(self.execute(theta, np.array([f]))["realized"] == 0.0 for f in near)


class AnalyticGraspSimulator(GraspSimulator):
    """The force balance itself as ground truth (for tests and quick runs)."""

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators

    def squeeze(self, mu: float, m: float, u: float) -> float:
        return float(squeeze_slip_mm(u, mu, m))

    def lift(self, mu: float, m: float, force: float) -> float:
        return 0.0 if force >= float(hold_force(mu, m, LIFT_ACCEL)) else 100.0
