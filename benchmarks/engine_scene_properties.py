"""Measure the insertion scene's observable properties in every engine, side by side.

For ``--truths`` instances drawn uniformly from the prior box (x_hole in [-10, 10] mm,
c in [0.7, 1.3], fixed seed) and each engine (MuJoCo, PyBullet, SAPIEN/PhysX) this runs

* the tap-boundary scan (``studies.engines.scan_boundary``: 0.25 mm grid over +-7 mm,
  then bisection to 1e-3 mm on both sides): offset of the pocket-reading boundary
  from hg(c), mean / SD / range over all scans (paper: MuJoCo +0.905, PyBullet +0.929,
  PhysX -0.209);
* the capture-window scan (``studies.engines.scan_capture_window``): per-truth capture
  half-width / w(c), mean and SD (paper: PyBullet 1.21 with SD 0.69 over 24 truths,
  PhysX 0.55);

and prints wall time per tap and per peg query and per instance build, with each
engine's times as a ratio to MuJoCo's, measured in this one run. ``--settings`` adds the
hand queries under each engine's default contact settings next to ours (what the
millimetre settings change).

Run: ``python benchmarks/engine_scene_properties.py [--truths 8] [--settings]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from probecommit.studies.engines import make_simulator, scan_boundary, scan_capture_window
from probecommit.tasks.insertion.model import half_gap

ENGINES = ("mujoco", "pybullet", "sapien")
PAPER_OFFSET = {"mujoco": 0.905, "pybullet": 0.929, "sapien": -0.209}
PAPER_RATIO = {"mujoco": 1.0, "pybullet": 1.21, "sapien": 0.55}


def truths(n: int, seed: int) -> list[tuple[float, float]]:
    rng = np.random.default_rng(seed)
    return [(float(x), float(c)) for x, c in zip(rng.uniform(-10, 10, n), rng.uniform(0.7, 1.3, n))]


def build_seconds(engine: str, inst: list[tuple[float, float]]) -> float:
    """Mean wall time to build one instance's scene (fresh simulator, first ``_instance``)."""
    sim = make_simulator(engine)
    t0 = time.perf_counter()
    for x, c in inst:
        sim._instance(x + 0.123, c)  # distinct keys: never a cached build
    return (time.perf_counter() - t0) / len(inst)


def _variant_row(args: tuple) -> str:
    """One settings variant, evaluated in its own process (Bullet keeps some settings process-global)."""
    label, engine, kwargs, inst = args
    hg = float(half_gap(1.0))
    taps = (10.0, 0.0, hg + 0.45, hg + 0.905 + 0.05)
    pegs = (0.0, 1.0, 1.6, 1.8)
    sim = make_simulator(engine, **kwargs)
    t = [sim.tap_reading(0.0, 1.0, u) for u in taps]
    p = [sim.peg_depth(0.0, 1.0, a) for a in pegs]
    b, cap = scan_boundary(sim, inst).summary(), scan_capture_window(sim, inst).summary()
    return (f"{label:>22} | " + " ".join(f"{v:9.4f}" for v in t) + " | " + " ".join(f"{v:7.3f}" for v in p)
            + f" | {b['delta']:+.4f} (SD {b['sd']:.4f}) | {cap['ratio_mean']:.3f} (SD {cap['ratio_sd']:.3f}, "
            f"{cap['sides_entering_beyond']} snag sides)")


def settings_section(inst: list[tuple[float, float]]) -> None:
    """Hand queries (x_hole = 0, c = 1) and both scans on ``inst``: engine defaults against ours."""
    import multiprocessing as mp

    from probecommit.engines.pybullet import MM_PHYSICS
    from probecommit.engines.sapien import MM_BODY

    sapien_defaults = dict(
        scene_config={"enable_enhanced_determinism": False},
        body={**MM_BODY, "sleep_threshold": 0.005, "solver_position_iterations": 10, "solver_velocity_iterations": 1,
              "linear_damping": 0.05, "angular_damping": 0.05, "joint_friction": 0.05},
        shape={"contact_offset": 0.01, "rest_offset": 0.0})
    variants = [
        ("pybullet ours", "pybullet", {}),
        ("pybullet all defaults", "pybullet", {"physics": {}, "collision_margin": None}),
        ("pybullet default margin", "pybullet", {"collision_margin": None}),
        ("pybullet default params", "pybullet", {"physics": {}}),
        ("pybullet 200 iters", "pybullet", {"physics": {**MM_PHYSICS, "numSolverIterations": 200}}),
        ("pybullet break 1e-4", "pybullet", {"physics": {**MM_PHYSICS, "contactBreakingThreshold": 1e-4}}),
        ("sapien ours", "sapien", {}),
        ("sapien defaults", "sapien", sapien_defaults),
        ("sapien box plate", "sapien", {"plate": "boxes"}),
    ]
    hg = float(half_gap(1.0))
    print(f"\nSettings, each variant in a fresh process. Hand queries at x_hole = 0, c = 1 (mm): taps at "
          f"u = 10, 0, hg+0.45 (chamfer), hg+0.955; pegs at a = 0, 1, 1.6, 1.8 (w = 1.7); then both scans "
          f"over {len(inst)} truths (hg = {hg}).")
    ctx = mp.get_context("spawn")
    with ctx.Pool(1, maxtasksperchild=1) as pool:
        for row in pool.imap(_variant_row, [(label, engine, kw, inst) for label, engine, kw in variants]):
            print(row, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--truths", type=int, default=8, help="instances drawn from the prior box")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--engines", nargs="+", default=list(ENGINES))
    ap.add_argument("--settings", action="store_true", help="also compare engine defaults with our settings")
    ap.add_argument("--settings-truths", type=int, default=8, help="truths scanned per settings variant")
    args = ap.parse_args()

    inst = truths(args.truths, args.seed)
    print(f"{args.truths} truths from the prior box (seed {args.seed}); tap grid 0.25 mm over +-7 mm, "
          f"bisection 1e-3 mm; capture steps 0.25 mm, bisection 1e-3 mm\n")
    print(f"{'engine':>9} | {'offset mean':>11} {'SD':>7} {'min':>7} {'max':>7} (paper) | "
          f"{'cap/w mean':>10} {'SD':>6} {'min':>6} {'max':>6} (paper) | {'tap ms':>7} {'peg ms':>7} {'build ms':>8}")
    times = {}
    for engine in args.engines:
        sim = make_simulator(engine)
        b = scan_boundary(sim, inst).summary()
        cap = scan_capture_window(sim, inst).summary()
        # Timed apart on fresh objects (uncached, build excluded): a fixed mix of queries.
        t_tap = _time_queries(engine, "tap_reading", inst)
        t_peg = _time_queries(engine, "peg_depth", inst)
        t_build = build_seconds(engine, inst[: min(4, len(inst))])
        times[engine] = (t_tap, t_peg, t_build)
        print(f"{engine:>9} | {b['delta']:+11.4f} {b['sd']:7.4f} {b['min']:+7.3f} {b['max']:+7.3f} "
              f"({PAPER_OFFSET[engine]:+.3f}) | {cap['ratio_mean']:10.3f} {cap['ratio_sd']:6.3f} {cap['ratio_min']:6.3f} "
              f"{cap['ratio_max']:6.3f} ({PAPER_RATIO[engine]:.2f}) | {1e3 * t_tap:7.2f} {1e3 * t_peg:7.2f} "
              f"{1e3 * t_build:8.2f}   [{sim.engine_calls['tap_reading']} taps, {sim.engine_calls['peg_depth']} pegs]")
    if "mujoco" in times:
        ref = times["mujoco"]
        print("\nwall time / MuJoCo's (same run): " + ", ".join(
            f"{e}: tap {t[0] / ref[0]:.2f}x, peg {t[1] / ref[1]:.2f}x, build {t[2] / ref[2]:.2f}x"
            for e, t in times.items() if e != "mujoco"))
    if args.settings:
        settings_section(inst[: args.settings_truths])


def _time_queries(engine: str, kind: str, inst: list[tuple[float, float]]) -> float:
    """Mean wall time of one uncached query over a fixed mix (inside, edge, outside)."""
    sim = make_simulator(engine)
    offsets = (0.0, 3.0, 5.4, 8.0) if kind == "tap_reading" else (0.0, 1.0, 1.6, 3.0)
    times = []
    for x, c in inst[: min(4, len(inst))]:
        sim._instance(x, c)  # build outside the timing
        for o in offsets:
            t0 = time.perf_counter()
            getattr(sim, kind)(x, c, x + o)
            times.append(time.perf_counter() - t0)
    return float(np.mean(times))


if __name__ == "__main__":
    main()
