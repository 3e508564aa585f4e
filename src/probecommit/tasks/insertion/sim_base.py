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

import time
from typing import Any, Iterable

import numpy as np

from probecommit.tasks.insertion.model import POCKET_DEPTH_MM

#: The peg fails if it reaches less than this fraction of the pocket depth.
ENTRY_DEPTH_FRACTION = 0.6


class InsertionSimulator:
    """Base class: cached deterministic queries + simulator-side noise and frame offset.

    Args:
        noise_sigma: Standard deviation of the tap noise the simulator adds (mm).
        aim_offset: Added to every committed aim on the simulator side (frame fault, mm).
    """

    engine = "abstract"

    def __init__(self, noise_sigma: float = 0.5, aim_offset: float = 0.0) -> None:
        if not (np.isfinite(noise_sigma) and noise_sigma >= 0):
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
        self.noise_sigma = float(noise_sigma)
        self.aim_offset = float(aim_offset)
        self._cache: dict[tuple[str, float, float, float], float] = {}
        self.engine_calls = {"tap_reading": 0, "peg_depth": 0}
        self.engine_seconds = 0.0

    # Named engine queries, deterministic given their arguments.
    def tap_reading(self, x_hole: float, c: float, u: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:  # pragma: no cover
        raise NotImplementedError

    def query(self, kind: str, x_hole: float, c: float, q: float) -> float:
        """Cached ``tap_reading`` or ``peg_depth``; the engine runs once per key."""
        key = (kind, float(x_hole), float(c), float(q))
        if key not in self._cache:
            start = time.perf_counter()
            value = float(getattr(self, kind)(float(x_hole), float(c), float(q)))
            self.engine_seconds += time.perf_counter() - start
            self.engine_calls[kind] += 1
            self._cache[key] = value
        return self._cache[key]

    def probe(self, theta: np.ndarray, u: float, rng: np.random.Generator) -> np.ndarray:
        reading = self.query("tap_reading", theta[0], theta[1], u)
        return np.array([reading + self.noise_sigma * rng.standard_normal()])

    def execute(self, theta: np.ndarray, action: float) -> dict[str, Any]:
        aim = float(action) + self.aim_offset
        depth = self.query("peg_depth", theta[0], theta[1], aim)
        if not np.isfinite(depth):
            raise FloatingPointError(f"{self.engine} peg_depth returned {depth} at aim {aim}")
        return {"realized": float(depth < ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM), "depth": depth}

    # Cache persistence, so replays and calibration never re-run a known query.
    def cache_records(self) -> list[dict[str, Any]]:
        return [
            {"engine": self.engine, "query": k[0], "x_hole": k[1], "c": k[2], "arg": k[3], "value": v}
            for k, v in self._cache.items()
        ]

    def load_cache(self, records: Iterable[dict[str, Any]]) -> None:
        for r in records:
            if r["engine"] == self.engine:
                self._cache[(r["query"], float(r["x_hole"]), float(r["c"]), float(r["arg"]))] = float(r["value"])


class AnalyticInsertionSimulator(InsertionSimulator):
    """The analytic model used as ground truth, with any tap boundary.

    Args:
        boundary_offset: Pocket-reading boundary ``hg(c) + boundary_offset`` (mm).
        capture_scale: Realized capture window as a multiple of ``w(c)``.
    """

    engine = "analytic"

    def __init__(self, boundary_offset: float = 0.905, capture_scale: float = 1.0, **kwargs) -> None:
        super().__init__(**kwargs)
        self.boundary_offset = float(boundary_offset)
        self.capture_scale = float(capture_scale)

    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        pocket = abs(u - x_hole) < 4.0 + 0.6 * c + self.boundary_offset
        return -POCKET_DEPTH_MM if pocket else 0.0

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        window = self.capture_scale * (0.6 * c + 1.1)
        return POCKET_DEPTH_MM if abs(a - x_hole) < window else 0.0
