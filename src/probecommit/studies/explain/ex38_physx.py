"""Which unreported PhysX setting gives the paper's 0.55 x capture window, and its boundary? (E214, E216; ex38,
issue #36; rules declared in ``docs/decisions.md``, "ex38", before any scan off our setting.)

Why: the paper's PhysX scene captures 0.55 x w(c) and reads the pocket out to hg - 0.209 mm; ours, 0.990 x and
hg + 0.898 mm. The paper reports no PhysX setting. A scene rebuilt "parameter for parameter" from MuJoCo's has no
contact offset to copy, so PhysX's default (0.01 m per shape, 8x the tip) is what such a rebuild keeps; a rest offset
inflates every shape. Each arm sweeps one setting, every other one ours, and at each point runs the engines study's
two scans on the development truths unchanged. The setting is chosen from the window the paper reports (the point
nearest 0.55, the grid refined by bisection where it brackets 0.55); the test is whether that one setting also gives
the paper's boundary, both within T18's own tolerances. Every key is :func:`summary` of the stored scan rows.
"""

from __future__ import annotations

import math
import time
from typing import Any, Callable, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.explain.pieces import Filled, Pieces, in_place
from probecommit.studies.paper_values import value as paper_value

#: The stored rows (``engines.scan_rows`` per point, with ``arm``, ``value``, ``cpu_s``), beside results.json.
STORED = "ex38_physx_rows.parquet"
#: Result group.
GROUP = "ex38_physx"
#: Each arm's declared grid (m, every shape's setting) and its experiment.
GRIDS = {"contact_offset": (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2),
         "rest_offset": (0.0, 5e-5, 1e-4, 2e-4, 3e-4, 5e-4)}
#: A quick run's grids: ours and the farthest declared point that is the arm's question (PhysX's default offset).
QUICK_GRIDS = {"contact_offset": (1e-4, 1e-2), "rest_offset": (0.0, 3e-4)}
EXPERIMENTS = {"contact_offset": "E214", "rest_offset": "E216"}
#: Our contact offset (``engines.sapien.MM_SHAPE``); the rest-offset arm keeps contacts this far beyond the rest offset.
OUR_CONTACT_M = 1e-4
#: Refinement: at most this many bisections, stopping once a point's ratio is within ``NEAR`` of the paper's.
BISECTIONS, NEAR = 4, 0.02
#: T18's tolerances on the PhysX capture ratio and offset (``studies.claims``, T18-engine-scans).
RATIO_TOLERANCE, OFFSET_TOLERANCE_MM = 0.1, 0.05


def shape_setting(arm: str, value: float) -> dict[str, float]:
    """The ``MM_SHAPE`` override of one point: the swept setting, the other one ours (contact above rest)."""
    if arm == "contact_offset":
        return {"contact_offset": float(value), "rest_offset": 0.0}
    if arm == "rest_offset":
        return {"contact_offset": float(value) + OUR_CONTACT_M, "rest_offset": float(value)}
    raise ValueError(f"unknown arm {arm!r}")


def scan_point(settings: dict[str, Any], truths: pd.DataFrame, noise_sigma: float,
               scan: dict[str, float]) -> pd.DataFrame:
    """The engines study's boundary and capture scans in SAPIEN with the given simulator overrides (``scene_config``,
    ``body``, ``shape``; ``engines.scan_rows``), or one ``failed`` row when a scan raises; its CPU seconds on every
    row. One function for every PhysX setting sweep (ex38's shape offsets, ex40's solver iterations)."""
    from probecommit.studies.engines import make_simulator, scan_boundary, scan_capture_window, scan_rows

    start = time.process_time()
    sim = make_simulator("sapien", noise_sigma=noise_sigma, **settings)
    try:
        boundary = scan_boundary(sim, truths, scan["step"], scan["half_range"], scan["tolerance"])
        rows = scan_rows("sapien", boundary, scan_capture_window(sim, truths))
    except RuntimeError as error:  # no pocket reading, or a peg entering out to the range's edge
        rows = pd.DataFrame({"kind": ["failed"], "error": [str(error)], "engine": ["sapien"]})
    return rows.assign(cpu_s=time.process_time() - start)


def point_rows(arm: str, value: float, truths: pd.DataFrame, noise_sigma: float, scan: dict[str, float]) -> pd.DataFrame:
    """One point: :func:`scan_point` with the point's shape setting, tagged with its arm and value."""
    rows = scan_point({"shape": shape_setting(arm, value)}, truths, noise_sigma, scan)
    cpu = rows.pop("cpu_s")
    return rows.assign(arm=arm, value=float(value), cpu_s=cpu)


def point_ratio(rows: pd.DataFrame) -> float:
    """A point's mean capture ratio (NaN for a failed point)."""
    ratio = rows.loc[rows["kind"] == "capture", "ratio"]
    return float(ratio.mean()) if len(ratio) else float("nan")


def _midpoint(lo: float, hi: float) -> float:
    """The bisection's next value: the log10 midpoint (the arithmetic one when a side is 0)."""
    return math.sqrt(lo * hi) if lo > 0 and hi > 0 else 0.5 * (lo + hi)


def _bracket(points: list[tuple[float, float]], target: float) -> tuple[float, float] | None:
    """The first adjacent pair (from the smallest value) whose ratios bracket ``target``."""
    for (v0, r0), (v1, r1) in zip(points, points[1:]):
        if np.isfinite(r0) and np.isfinite(r1) and (r0 - target) * (r1 - target) <= 0:
            return v0, v1
    return None


def sweep(arm: str, grid: Sequence[float], evaluate: Callable[[str, float], pd.DataFrame],
          bisections: int = BISECTIONS) -> pd.DataFrame:
    """The arm's grid, then the declared refinement: bisect the first bracket of the paper's ratio until a point
    is within ``NEAR`` of it or ``bisections`` are spent. ``evaluate(arm, value)`` gives a point's rows."""
    target = float(paper_value("T18-engine-scans.sapien_ratio"))
    parts = {float(v): evaluate(arm, float(v)) for v in grid}
    ratios = {v: point_ratio(p) for v, p in parts.items()}
    pair = _bracket(sorted(ratios.items()), target)
    for _ in range(bisections if pair else 0):
        if any(abs(r - target) <= NEAR for r in ratios.values()):
            break
        mid = _midpoint(*pair)
        parts[mid] = evaluate(arm, mid)
        ratios[mid] = point_ratio(parts[mid])
        lo, hi = pair
        pair = (lo, mid) if (ratios[lo] - target) * (ratios[mid] - target) <= 0 else (mid, hi)
    return pd.concat([parts[v] for v in sorted(parts)], ignore_index=True)


def point_keys(rows: pd.DataFrame) -> dict[str, float]:
    """One point's keys: its setting, boundary offset and SD, capture ratio and SD, sides entering beyond, CPU."""
    from probecommit.studies.engines import scan_summaries

    out = {"value": float(rows["value"].iloc[0]), "cpu_s": float(rows["cpu_s"].iloc[0])}
    if (rows["kind"] == "failed").any():
        return {**out, "failed": 1}
    s = scan_summaries(rows.drop(columns=["arm", "value", "cpu_s"]))["sapien"]
    return {**out, "failed": 0, "delta": s["boundary"]["delta"], "delta_sd": s["boundary"]["sd"],
            "ratio": s["capture"]["ratio_mean"], "ratio_sd": s["capture"]["ratio_sd"],
            "sides_entering_beyond": s["capture"]["sides_entering_beyond"]}


def arm_keys(rows: pd.DataFrame) -> dict[str, Any]:
    """One arm's keys: every point (``p<i>.``, by value), the point chosen by the paper's window and the rule."""
    target = float(paper_value("T18-engine-scans.sapien_ratio"))
    paper_delta = float(paper_value("T18-engine-scans.sapien_offset"))
    points = [point_keys(part) for _, part in rows.groupby("value", sort=True)]
    out: dict[str, Any] = {"points": len(points)}
    for i, p in enumerate(points):
        out.update({f"p{i}.{k}": v for k, v in p.items()})
    scanned = [p for p in points if not p["failed"]]
    if not scanned:
        return {**out, "holds": 0}
    chosen = min(scanned, key=lambda p: abs(p["ratio"] - target))  # a tie goes to the smallest setting
    ratio_ok = int(abs(chosen["ratio"] - target) <= RATIO_TOLERANCE)
    delta_ok = int(abs(chosen["delta"] - paper_delta) <= OFFSET_TOLERANCE_MM)
    return {**out, **{f"chosen.{k}": chosen[k] for k in ("value", "delta", "ratio", "ratio_sd")},
            "chosen.ratio_passes": ratio_ok, "chosen.offset_passes": delta_ok, "holds": ratio_ok * delta_ok,
            "cpu_s": float(sum(p["cpu_s"] for p in points))}


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """E214's and E216's keys (``<arm>.``) from the stored rows (the step and ``verify``)."""
    out: dict[str, Any] = {}
    for arm, part in rows.groupby("arm", sort=False):
        out.update({f"{arm}.{k}": v for k, v in arm_keys(part).items()})
    return out


def development_truths(protocol: Any, count: int) -> pd.DataFrame:
    """The engines study's development truths (the first ``count`` of them; 0: all)."""
    from probecommit.runner.build import build_model
    from probecommit.runner.instances import draw_instances

    cfg = protocol.run_config("development", "development", "development", "random")
    truths = draw_instances(cfg, build_model(cfg))
    return truths.head(count) if count else truths


def arm_rows(protocol: Any, arm: str, grid: Sequence[float], count: int, refine: bool) -> pd.DataFrame:
    """One arm's sweep, each point in a process of its own (its PhysX scenes leave with it)."""
    from probecommit.runner.aside import in_own_process

    truths = development_truths(protocol, count)
    scan = dict(protocol.scan)

    def evaluate(a: str, v: float) -> pd.DataFrame:
        return in_own_process(point_rows, a, v, truths, protocol.noise_sigma, scan)

    return sweep(arm, grid, evaluate, BISECTIONS if refine else 0)


def pieces(job: Any) -> Pieces | None:
    """The sweep cut into its arms (``pieces``), each arm's grid and bisection one piece (the bisection reads the
    grid's ratios); None without SAPIEN or when the settings skip it. Reads only the protocol and the settings."""
    import importlib.util

    count = int(job.cfg["ex38_truths_quick" if job.quick else "ex38_truths"])
    if count < 0 or importlib.util.find_spec("sapien") is None:
        return None
    grids = QUICK_GRIDS if job.quick else GRIDS
    job.progress("explain: PhysX contact and rest offset sweeps (E214, E216)", 0, 1)
    refine = not job.quick
    calls = [(arm_rows, (job.p, arm, grid, count, refine)) for arm, grid in grids.items()]
    costs = [len(grid) + (BISECTIONS if refine else 0) for grid in grids.values()]  # the points it may scan
    return Pieces(calls, costs, combine)


def combine(parts: list[pd.DataFrame]) -> Filled:
    """The arms' rows in arm order, stored, and their keys."""
    rows = pd.concat(parts, ignore_index=True)
    return {"res": {GROUP: summary(rows)}, "stored": {STORED: rows}}


def run(job: Any) -> None:
    """The explain step (reads only the protocol): stored rows and keys. Skipped without SAPIEN. The target sets
    its arms aside as jobs of their own (``Explain.split(pieces)``)."""
    in_place(job, pieces)


__all__: Sequence[str] = ("run", "pieces", "combine", "summary", "sweep", "point_rows", "scan_point", "shape_setting", "GRIDS", "STORED", "GROUP")
