"""Measure the MuJoCo insertion scene's directly observable properties.

For a few instances ``(x_hole, c)`` this bisects, on each side of the hole,

* the tap boundary: the lateral offset ``|u - x_hole|`` where the tap reading flips
  from the pocket floor to the plate top, reported as an offset from ``hg(c)``
  (the paper reports ``hg + 0.905`` mm for MuJoCo, the same on every instance);
* the capture half-width: the offset ``|a - x_hole|`` beyond which the peg no longer
  enters (reaches less than 60% of the pocket depth), against ``w(c) = 0.6 c + 1.1`` mm;

and prints the mean wall time of one tap and one peg query, side by side with the
time to compile one instance's model.

Run: ``python benchmarks/mujoco_scene_properties.py [--tol 0.001]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from probecommit.tasks.insertion.model import POCKET_DEPTH_MM, capture_half_width, half_gap
from probecommit.tasks.insertion.sim_base import ENTRY_DEPTH_FRACTION
from probecommit.tasks.insertion.sim_mujoco import MujocoInsertionSimulator

INSTANCES = [(0.0, 0.7), (0.0, 1.0), (0.0, 1.3), (-7.3, 0.85), (4.1, 1.15), (9.6, 0.72)]


def bisect(pred, lo: float, hi: float, tol: float) -> float:
    """Largest offset with ``pred`` true, given ``pred(lo)`` true and ``pred(hi)`` false."""
    if not pred(lo) or pred(hi):
        raise RuntimeError(f"bracket [{lo}, {hi}] does not straddle the flip")
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pred(mid) else (lo, mid)
    return 0.5 * (lo + hi)


class Timed:
    """Wraps a query and records its wall time."""

    def __init__(self, fn):
        self.fn, self.times = fn, []

    def __call__(self, *args):
        t0 = time.perf_counter()
        out = self.fn(*args)
        self.times.append(time.perf_counter() - t0)
        return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tol", type=float, default=1e-3, help="bisection tolerance (mm)")
    args = ap.parse_args()

    sim = MujocoInsertionSimulator()
    tap, peg = Timed(sim.tap_reading), Timed(sim.peg_depth)
    compile_times = []
    half_depth = -0.5 * POCKET_DEPTH_MM
    entry = ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM

    print(f"{'x_hole':>7} {'c':>5} {'hg':>6} | {'tap off -':>9} {'tap off +':>9} (paper +0.905)"
          f" | {'w(c)':>6} {'cap -':>6} {'cap +':>6} {'cap/w':>6}")
    offsets, ratios = [], []
    for x, c in INSTANCES:
        t0 = time.perf_counter()
        sim._instance(x, c)  # compile once, timed on its own
        compile_times.append(time.perf_counter() - t0)
        hg, w = float(half_gap(c)), float(capture_half_width(c))
        row_off, row_cap = [], []
        for sgn in (-1.0, 1.0):
            row_off.append(bisect(lambda d: tap(x, c, x + sgn * d) < half_depth, hg - 1.0, hg + 3.0, args.tol) - hg)
            row_cap.append(bisect(lambda d: peg(x, c, x + sgn * d) >= entry, 0.0, hg, args.tol))
        offsets += row_off
        ratios += [v / w for v in row_cap]
        print(f"{x:7.2f} {c:5.2f} {hg:6.3f} | {row_off[0]:+9.4f} {row_off[1]:+9.4f}"
              f"                | {w:6.3f} {row_cap[0]:6.4f} {row_cap[1]:6.4f} {np.mean(row_cap) / w:6.3f}")
    print(f"\ntap boundary offset from hg: mean {np.mean(offsets):+.4f} mm, "
          f"range [{min(offsets):+.4f}, {max(offsets):+.4f}] (paper: +0.905, identical on all scans)")
    print(f"capture half-width / w(c): mean {np.mean(ratios):.3f}, range [{min(ratios):.3f}, {max(ratios):.3f}]")
    tt, tp, tc = np.mean(tap.times), np.mean(peg.times), np.mean(compile_times)
    print(f"\nwall time: tap {tt * 1e3:.2f} ms/query ({len(tap.times)} queries), "
          f"peg {tp * 1e3:.2f} ms/query ({len(peg.times)}), model compile {tc * 1e3:.2f} ms/instance")
    print(f"ratios: peg/tap {tp / tt:.2f}, compile/tap {tc / tt:.2f}")


if __name__ == "__main__":
    main()
