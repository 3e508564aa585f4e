"""Boundary scan: where does the simulator's tap reading flip from pocket to top?

For each development truth, the tap reading is sampled against lateral offset from
the hole centre on a grid (0.25 mm steps over +-7 mm), then each side's outermost
pocket-to-top flip is refined by bisection. The fitted ``delta`` of the corrected
boundary ``hg(c) + delta`` is the mean over all scans (two per truth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from probecommit.tasks.insertion.model import POCKET_DEPTH_MM, half_gap

#: A reading below this height (mm) is a pocket reading.
POCKET_THRESHOLD_MM = -POCKET_DEPTH_MM / 2


@dataclass
class ScanResult:
    """All scans and the fitted boundary offset."""

    scans: pd.DataFrame  # instance_id, x_hole, c, side, boundary (|u - x| at the flip), offset (boundary - hg)
    grid: pd.DataFrame  # instance_id, offset_from_hole, reading

    @property
    def delta(self) -> float:
        return float(self.scans["offset"].mean())

    def summary(self) -> dict[str, float]:
        off = self.scans["offset"]
        return {
            "delta": float(off.mean()),
            "sd": float(off.std(ddof=1)) if len(off) > 1 else 0.0,
            "min": float(off.min()),
            "max": float(off.max()),
            "scans": int(len(off)),
            "shift_vs_deployed_mm": float(off.mean() + 1.2),
        }


def _is_pocket(simulator, x_hole: float, c: float, u: float) -> bool:
    return simulator.query("tap_reading", x_hole, c, u) < POCKET_THRESHOLD_MM


def scan_offsets(step: float, half_range: float) -> np.ndarray:
    """The scan grid's tap offsets from the hole centre."""
    return np.round(np.arange(-half_range, half_range + step / 2, step), 10)


def scan_instance(simulator, x_hole: float, c: float, step: float, half_range: float, tolerance: float):
    """Grid and bisection scan of one truth; returns (grid rows, per-side boundary distances)."""
    offsets = scan_offsets(step, half_range)
    readings = np.array([simulator.query("tap_reading", x_hole, c, x_hole + o) for o in offsets])
    pocket = readings < POCKET_THRESHOLD_MM
    if not pocket.any():
        raise RuntimeError(f"scan of x_hole={x_hole:.3f}, c={c:.3f}: no grid tap read the pocket")
    sides = {}
    for side, sign in (("left", -1.0), ("right", 1.0)):
        # Outermost pocket grid point on this side, and the first top point beyond it.
        idx = np.flatnonzero(pocket & (sign * offsets >= 0))
        inner = float(np.max(sign * offsets[idx]))
        outer = inner + step
        if outer > half_range + 1e-9:
            raise RuntimeError(f"scan of x_hole={x_hole:.3f}: pocket reading at the edge of the +-{half_range} mm range")
        while outer - inner > tolerance:
            mid = 0.5 * (inner + outer)
            if _is_pocket(simulator, x_hole, c, x_hole + sign * mid):
                inner = mid
            else:
                outer = mid
        sides[side] = 0.5 * (inner + outer)
    grid = pd.DataFrame({"offset_from_hole": offsets, "reading": readings})
    return grid, sides


def boundary_scan(simulator, instances: pd.DataFrame, step: float = 0.25, half_range: float = 7.0, tolerance: float = 1e-3) -> ScanResult:
    """Scan every truth of ``instances`` (columns ``instance_id, true_x_hole, true_c``)."""
    rows, grids = [], []
    if simulator.parallel_queries:  # every truth's grid taps are needed: run them in engine threads
        offsets = scan_offsets(step, half_range)
        simulator.prefetch([simulator.query_key("tap_reading", x, c, x + o) for x, c in
                            zip(instances["true_x_hole"].astype(float), instances["true_c"].astype(float)) for o in offsets])
    for _, inst in instances.iterrows():
        x, c = float(inst["true_x_hole"]), float(inst["true_c"])
        grid, sides = scan_instance(simulator, x, c, step, half_range, tolerance)
        grids.append(grid.assign(instance_id=inst["instance_id"]))
        for side, dist in sides.items():
            rows.append({"instance_id": inst["instance_id"], "x_hole": x, "c": c, "side": side,
                         "boundary": dist, "offset": dist - float(half_gap(c))})
    return ScanResult(pd.DataFrame(rows), pd.concat(grids, ignore_index=True))


def scan_development(protocol, simulator, step: float | None = None) -> ScanResult:
    """The protocol's scan: every development truth, at the protocol's step, range and tolerance."""
    from probecommit.runner.build import build_model
    from probecommit.runner.instances import draw_instances

    cfg = protocol.run_config("development", "development", "development", "random")
    instances = draw_instances(cfg, build_model(cfg))
    return boundary_scan(simulator, instances, step or protocol.scan["step"], protocol.scan["half_range"],
                         protocol.scan["tolerance"])
