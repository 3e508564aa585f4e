"""Shared ground-truth plumbing for insertion simulators.

An engine simulator implements two deterministic named queries in mm:
``tap_reading(x_hole, c, u)`` (height where the tap probe stops, relative to the
plate top) and ``peg_depth(x_hole, c, a)`` (how far below the plate top the peg
reached). This base caches both per distinct query, so the engine runs once per
(instance, tap position) and once per (instance, aim), never per episode, budget or
method; adds the simulator-side tap noise from the episode's generator; and applies
the simulator-side frame offset of the frame fault.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probecommit.tasks.base import NoisySimulator
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, POCKET_DEPTH_MM

#: The peg fails if it reaches less than this fraction of the pocket depth.
ENTRY_DEPTH_FRACTION = 0.6


class InsertionSimulator(NoisySimulator):
    """Base class: cached deterministic queries + simulator-side noise and frame offset.

    Args:
        noise_sigma: Standard deviation of the tap noise the simulator adds (mm).
        aim_offset: Added to every committed aim on the simulator side (frame fault, mm).
    """

    engine = "abstract"
    answer_independent_settings = ("noise_sigma", "aim_offset")  # the offset moves the aim before the query

    def __init__(self, noise_sigma: float = 0.5, aim_offset: float = 0.0) -> None:
        super().__init__(noise_sigma)
        self.aim_offset = float(aim_offset)
        self.engine_calls = {"tap_reading": 0, "peg_depth": 0}

    # Named engine queries, deterministic given their arguments.
    def tap_reading(self, x_hole: float, c: float, u: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:  # pragma: no cover
        raise NotImplementedError

    @staticmethod
    def query_key(kind: str, x_hole: float, c: float, q: float) -> tuple:
        """The cache key of ``query(kind, x_hole, c, q)`` (for :meth:`prefetch`)."""
        return (kind, (float(x_hole), float(c)), (float(q),))

    def query(self, kind: str, x_hole: float, c: float, q: float) -> float:
        """Cached ``tap_reading`` or ``peg_depth`` in mm; the engine runs once per key."""
        return float(self.cached_key(self.query_key(kind, x_hole, c, q))[0])

    def probe_query_key(self, theta: np.ndarray, u: np.ndarray) -> tuple:
        """The cache key of the engine query behind ``probe(theta, u, ...)`` (for :meth:`prefetch`)."""
        return self.query_key("tap_reading", theta[0], theta[1], np.asarray(u).item(0))

    def execute_query_key(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> tuple:
        """The cache key of the engine query behind ``execute(theta, action)`` (for :meth:`prefetch`)."""
        return self.query_key("peg_depth", theta[0], theta[1], float(np.asarray(action).item(0)) + self.aim_offset)

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        reading = float(self.cached_key(self.probe_query_key(theta, u))[0])
        return np.array([reading + self.noise_sigma * rng.standard_normal()])

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        key = self.execute_query_key(theta, action)
        depth = self._depth(key)
        return {"realized": float(depth < ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM), "depth": depth}

    def _depth(self, key: tuple) -> float:
        """The peg depth the cached query ``key`` answers (finite, else an error naming the aim)."""
        depth = float(self.cached_key(key)[0])
        if not math.isfinite(depth):
            raise FloatingPointError(f"{self.engine} peg_depth returned {depth} at aim {key[2][0]}")
        return depth

    def realized_many(self, thetas: np.ndarray, actions: np.ndarray,
                      contexts: np.ndarray | None = None) -> list[float | Exception]:
        """:meth:`execute`'s realized failure per row (``CachedSimulator.realized_many``), its query
        keys made for every row at once: the same keys, engine calls and values, without a call
        of ``execute`` per (instance, aim) (~20,000 in a calibration at E = 3072, issue 42).
        A subclass with its own ``execute`` or key is executed row by row."""
        cls = type(self)
        if (cls.execute is not InsertionSimulator.execute or cls.execute_query_key is not InsertionSimulator.execute_query_key
                or not len(thetas)):
            return super().realized_many(thetas, actions, contexts)
        thetas = np.asarray(thetas, dtype=float)
        aims = (np.asarray(actions, dtype=float).reshape(len(thetas), -1)[:, 0] + self.aim_offset).tolist()
        entry = ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM
        out: list[float | Exception] = []
        for x, c, aim in zip(thetas[:, 0].tolist(), thetas[:, 1].tolist(), aims):
            try:
                out.append(float(self._depth(("peg_depth", (x, c), (aim,))) < entry))
            except Exception as exc:  # noqa: BLE001 - the caller marks the episodes failed
                out.append(exc)
        return out


class AnalyticInsertionSimulator(InsertionSimulator):
    """The analytic model used as ground truth, with any tap boundary.

    Args:
        boundary_offset: Pocket-reading boundary ``hg(c) + boundary_offset`` (mm).
        capture_scale: Realized capture window as a multiple of ``w(c)``.
    """

    engine = "analytic"
    thread_safe = True  # pure Python and NumPy, no state shared between simulators

    def __init__(self, boundary_offset: float = PAPER_DELTA_MM, capture_scale: float = 1.0, **kwargs) -> None:
        super().__init__(**kwargs)
        self.boundary_offset = float(boundary_offset)
        self.capture_scale = float(capture_scale)

    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        pocket = abs(u - x_hole) < 4.0 + 0.6 * c + self.boundary_offset
        return -POCKET_DEPTH_MM if pocket else 0.0

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        window = self.capture_scale * (0.6 * c + 1.1)
        return POCKET_DEPTH_MM if abs(a - x_hole) < window else 0.0
