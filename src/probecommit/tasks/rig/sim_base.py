"""The simulated rig's shared plumbing: cached touch-switch queries, misreads, the window outcome.

An engine answers two deterministic named queries in mm: ``tap_reading(x_hole, c, u)``
(where the touch-switch descent stopped: 0 on the block, ``-ALLOWANCE_MM`` through the
opening) and ``tool_depth(x_hole, c, a)`` (how far below the block top the committed
tool reached). The base caches both per query, adds the switch's misreads and any
reading noise from the episode's generator, and scores an aim as the paper's rig did:
failure when the aim is outside the model's window of the measured centre; whether the
tool entered (reached 60 % of the pocket depth) is returned beside it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.tasks.insertion.sim_base import ENTRY_DEPTH_FRACTION, InsertionSimulator
from probecommit.tasks.rig.model import (ALLOWANCE_MM, DESCENT_STEP_MM, POCKET_DEPTH_MM, TOOL_RADIUS_MM,
                                         rig_half_gap, rig_window)


class RigSimulator(InsertionSimulator):
    """Base class of the simulated rigs.

    Args:
        noise_sigma: Gaussian noise added to a reading (mm); 0 for a clean switch.
        misread_rate: Probability that a tap reports the other outcome.
        aim_offset: Added to every committed aim (frame fault, mm).
    """

    engine = "abstract"
    answer_independent_settings = ("noise_sigma", "aim_offset", "misread_rate")  # misreads flip an answer after the query

    def __init__(self, noise_sigma: float = 0.0, misread_rate: float = 0.01, aim_offset: float = 0.0) -> None:
        super().__init__(noise_sigma=noise_sigma, aim_offset=aim_offset)
        if not 0 <= misread_rate < 1:
            raise ValueError(f"misread_rate must be in [0, 1), got {misread_rate!r}")
        self.misread_rate = float(misread_rate)
        self.engine_calls = {"tap_reading": 0, "tool_depth": 0}

    def tool_depth(self, x_hole: float, c: float, a: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        reading = self.query("tap_reading", theta[0], theta[1], float(np.ravel(u)[0]))
        # Both draws every time, so a change of rate never shifts the episode's stream.
        flip, noise = rng.random(), rng.standard_normal()
        if flip < self.misread_rate:
            reading = 0.0 if reading < -ALLOWANCE_MM / 2 else -ALLOWANCE_MM
        return np.array([reading + self.noise_sigma * noise])

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        aim = float(np.ravel(action)[0]) + self.aim_offset
        depth = self.query("tool_depth", theta[0], theta[1], aim)
        if not np.isfinite(depth):
            raise FloatingPointError(f"{self.engine} tool_depth returned {depth} at aim {aim}")
        in_window = abs(aim - float(theta[0])) < float(rig_window(theta[1]))
        return {"realized": float(not in_window), "entered": bool(depth >= ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM),
                "depth": depth}


class AnalyticRigSimulator(RigSimulator):
    """The rig's geometry in closed form: a flat tool of radius r fits when ``|u - x| < hg - r``."""

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators

    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        fits = abs(u - x_hole) < float(rig_half_gap(c)) - TOOL_RADIUS_MM
        return -ALLOWANCE_MM if fits else 0.0

    def tool_depth(self, x_hole: float, c: float, a: float) -> float:
        fits = abs(a - x_hole) < float(rig_half_gap(c)) - TOOL_RADIUS_MM
        return POCKET_DEPTH_MM if fits else 0.0


#: Descent heights (mm) of a tap: from 2 mm above the top in 0.5 mm steps to the allowance.
def descent_heights(stop: float) -> np.ndarray:
    n = int(round((2.0 + stop) / DESCENT_STEP_MM))
    return 2.0 - DESCENT_STEP_MM * np.arange(n + 1)
