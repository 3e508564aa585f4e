"""PyBullet's capture window against a compliant plate contact (E218; ex39, issue #36; rule declared in
``docs/decisions.md``, "ex39", before the sweep's numbers were computed).

Why: the paper's PyBullet captures the peg over 1.21 x w(c) with an SD of 0.69 of that ratio across the 24
development truths, ours over 1.000 x w(c) with SD 0.0002 (T18). A window wider than the geometric one, varying
from truth to truth, is what a compliant contact can give: the peg sinks into the plate's top and its edge catches
the chamfer from farther out. The paper reports none of PyBullet's contact settings; ours and PyBullet's default
are a rigid contact. This step sweeps the plate's ``contactStiffness`` (with a damping ratio) over a declared grid,
runs the engines study's two scans unchanged at each point on its 24 development truths, and picks the point by the
capture ratio the paper reports (a scene property it prints); E218 then asks whether, at that point, the tap
boundary still matches the paper's and the per-truth ratio spreads as the paper's does.
Every key is :func:`summary` of the stored scan rows (:data:`STORED`), so verify recomputes them.
"""

from __future__ import annotations

import functools
import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.engines import make_simulator, scan_boundary, scan_capture_window, scan_rows, scan_summaries
from probecommit.studies.explain.pieces import Filled, Pieces, in_place
from probecommit.studies.paper_values import value as paper_value
from probecommit.tasks.insertion.sim_mujoco import PEG_MASS_KG

#: The stored scan rows (``studies.engines.scan_rows`` per grid point, and the published rigid scan), beside
#: results.json.
STORED = "ex39_pybullet_rows.parquet"
#: Result group.
GROUP = "ex39_pybullet"
#: The declared grid (docs/decisions.md, "ex39"): the plate's contact stiffness (N/m) and the damping ratio of the
#: peg on it, besides the rigid point (neither set: PyBullet's default and ours).
STIFFNESS = (1e5, 1e4, 3e3, 1e3, 5e2, 3e2)
ZETA = (0.1, 1.0)
#: E218's rule: the boundary within T18's tolerance of the paper's, the ratio's SD at least this share of the paper's.
BOUNDARY_TOLERANCE_MM = 0.05
SD_FRACTION = 0.5
#: The published scan's rows in :data:`STORED` (``point``), compared with the rigid point's.
PUBLISHED = "published"
RIGID = "rigid"


def label(stiffness: float, zeta: float) -> str:
    """A grid point's name in keys: ``k<N/m>_z<100 zeta>`` (``k1000_z010``)."""
    return f"k{stiffness:.0f}_z{round(zeta * 100):03d}"


def grid() -> list[tuple[str, float, float]]:
    """The declared points in grid order: (name, stiffness, zeta), the rigid point first (NaN, NaN)."""
    return [(RIGID, float("nan"), float("nan"))] + [(label(k, z), k, z) for z in ZETA for k in STIFFNESS]


def plate_contact(stiffness: float, zeta: float) -> dict[str, float] | None:
    """The plate's ``changeDynamics`` keywords at a grid point (None at the rigid point): damping
    ``zeta * 2 sqrt(k m)`` with m the peg's mass, so zeta is the peg's damping ratio on the contact."""
    if np.isnan(stiffness):
        return None
    return {"contactStiffness": float(stiffness),
            "contactDamping": float(zeta * 2.0 * np.sqrt(stiffness * PEG_MASS_KG))}


def published_truths(rows: pd.DataFrame, count: int | None = None) -> pd.DataFrame:
    """The engines study's development truths (``instance_id, true_x_hole, true_c``) from its stored PyBullet
    capture rows, in their order; the first ``count`` only when given."""
    part = rows[(rows["engine"] == "pybullet") & (rows["kind"] == "capture")]
    out = part[["instance_id", "x_hole", "c"]].rename(columns={"x_hole": "true_x_hole", "c": "true_c"})
    return out.head(count).reset_index(drop=True) if count is not None else out.reset_index(drop=True)


def point_rows(truths: pd.DataFrame, stiffness: float, zeta: float, scan: dict[str, float],
               noise_sigma: float) -> tuple[pd.DataFrame, float]:
    """One grid point: the engines study's boundary and capture scans of ``truths`` in a fresh PyBullet simulator
    with that plate contact; the scan rows (``scan_rows``) and the CPU seconds they took."""
    return scan_point(truths, scan, noise_sigma, plate_contact=plate_contact(stiffness, zeta))


def scan_point(truths: pd.DataFrame, scan: dict[str, float], noise_sigma: float,
               **settings: Any) -> tuple[pd.DataFrame, float]:
    """The engines study's boundary and capture scans of ``truths`` in a fresh PyBullet simulator built with
    ``settings`` (the simulator's keywords: one swept setting, all else the published scene); the scan rows
    (``scan_rows``) and the CPU seconds they took. Shared by every PyBullet setting sweep (E218, E228)."""
    start = time.process_time()
    sim = make_simulator("pybullet", noise_sigma=noise_sigma, **settings)
    try:
        boundary = scan_boundary(sim, truths, scan["step"], scan["half_range"], scan["tolerance"])
        capture = scan_capture_window(sim, truths)
    finally:
        sim.close()
    return scan_rows("pybullet", boundary, capture), time.process_time() - start


def grid_point(truths: pd.DataFrame, index: int, scan: dict[str, float], noise_sigma: float) -> tuple[pd.DataFrame, float]:
    """Grid point ``index``'s scan rows (columns ``point, index, stiffness, zeta`` added) and their CPU seconds."""
    name, k, z = grid()[index]
    rows, cpu = point_rows(truths, k, z, scan, noise_sigma)
    return rows.assign(point=name, index=index, stiffness=k, zeta=z), cpu


def grid_points(truths: pd.DataFrame, indices: Sequence[int], scan: dict[str, float],
                noise_sigma: float) -> list[tuple[pd.DataFrame, float]]:
    """:func:`grid_point` of each of ``indices``, in that order (a piece of the sweep, ``pieces``)."""
    return [grid_point(truths, index, scan, noise_sigma) for index in indices]


def sweep(truths: pd.DataFrame, scan: dict[str, float], noise_sigma: float, points: Sequence[str] | None = None,
          progress: Any = None) -> pd.DataFrame:
    """The grid's scan rows (columns ``point, index, stiffness, zeta`` added), the points named in ``points``
    only when given (the whole grid otherwise)."""
    step = progress or (lambda *a: None)
    parts = []
    for index, (name, _, _) in enumerate(grid()):
        if points is not None and name not in points:
            continue
        rows, cpu = grid_point(truths, index, scan, noise_sigma)
        step(f"explain: E218 point {name} ({cpu:.0f} s CPU)", index + 1, len(grid()))
        parts.append(rows)
    return pd.concat(parts, ignore_index=True)


def point_keys(rows: pd.DataFrame) -> dict[str, float]:
    """One point's scan summary: the boundary's delta and SD, the capture ratio's mean, SD, min, max, and the sides
    where an aim beyond the first failure entered again."""
    s = scan_summaries(rows.assign(engine="pybullet"))["pybullet"]
    b, c = s["boundary"], s["capture"]
    return {"delta": b["delta"], "delta_sd": b["sd"], "ratio_mean": c["ratio_mean"], "ratio_sd": c["ratio_sd"],
            "ratio_min": c["ratio_min"], "ratio_max": c["ratio_max"], "truths": c["truths"],
            "sides_entering_beyond": c["sides_entering_beyond"]}


def same_scans(a: pd.DataFrame, b: pd.DataFrame) -> bool:
    """Whether two points' boundary and capture rows are equal (the rigid rerun against the published scan)."""
    cols = ["kind", "instance_id", "side", "offset", "half_width", "window"]
    a, b = (x[cols].sort_values(cols[:3]).reset_index(drop=True) for x in (a, b))
    return len(a) == len(b) and bool(a.equals(b))


def sweep_keys(rows: pd.DataFrame, settings: Sequence[str], reference: str) -> dict[str, float]:
    """A PyBullet setting sweep's keys from its stored rows (E218, E228): every point's summary (``<point>.*``),
    the point nearest the paper's capture ratio (``chosen.*`` with its ``settings`` columns, ties to the first in
    grid order), the boundary and spread parts of the rule, and ``<reference>_equals_published`` (the
    ``reference`` point's rows, our published scene, against the published scan's, when stored)."""
    paper_ratio, paper_sd = paper_value("T18-engine-scans.pybullet_ratio"), paper_value("T18-engine-scans.pybullet_ratio_sd")
    paper_delta = paper_value("T18-engine-scans.pybullet_offset")
    out: dict[str, float] = {"sd_fraction": SD_FRACTION, "boundary_tolerance_mm": BOUNDARY_TOLERANCE_MM}
    swept = rows[rows["point"] != PUBLISHED]
    order = swept.drop_duplicates("point").sort_values("index")
    per = {name: point_keys(swept[swept["point"] == name]) for name in order["point"]}
    for name, keys in per.items():
        out.update({f"{name}.{k}": v for k, v in keys.items()})
    chosen = min(order.itertuples(), key=lambda r: (abs(per[r.point]["ratio_mean"] - paper_ratio), r.index))
    c = per[chosen.point]
    out.update({f"chosen.{k}": v for k, v in c.items()})
    out.update({f"chosen.{k}": float(getattr(chosen, k)) for k in settings})
    out.update({"chosen.index": int(chosen.index), "points": int(len(per))})
    out["boundary_ok"] = int(abs(c["delta"] - paper_delta) <= BOUNDARY_TOLERANCE_MM)
    out["spread_ok"] = int(c["ratio_sd"] >= SD_FRACTION * paper_sd)
    published = rows[rows["point"] == PUBLISHED]
    if len(published) and reference in per:
        out[f"{reference}_equals_published"] = int(same_scans(swept[swept["point"] == reference], published))
    return out


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """E218's keys from the stored rows (:func:`sweep_keys` over stiffness and zeta, the rigid point our scene) and
    ``holds``: rule parts (a) and (b)."""
    out = sweep_keys(rows, ("stiffness", "zeta"), RIGID)
    out["holds"] = int(out["boundary_ok"] and out["spread_ok"])
    return out


def _published_scans(job: Any) -> pd.DataFrame | None:
    """The engines study's stored scan rows under the job's root (None before that study ran)."""
    path = Path(job.root) / "engines" / "results" / "engine_scans.parquet"
    return pd.read_parquet(path) if path.is_file() else None


def _published_rows(published: pd.DataFrame, truths: pd.DataFrame) -> pd.DataFrame:
    """The engines study's published PyBullet scan rows of ``truths``, as a sweep's point :data:`PUBLISHED` (the
    check that our setting's point reproduces them)."""
    mine = published[(published["engine"] == "pybullet") & published["instance_id"].isin(truths["instance_id"])]
    return mine.drop(columns="engine").assign(point=PUBLISHED, index=-1)


def run_sweep(job: Any, truths_key: str, title: str, sweep_rows: Any, stored: str, group: str, keys: Any,
              points: Sequence[str] | None = None) -> None:
    """A PyBullet setting sweep as one explain step (E228): ``sweep_rows(truths, scan, noise_sigma, points,
    progress)`` on the engines study's stored development truths (``job.cfg[truths_key]``, ``<truths_key>_quick``
    in a quick run), the published scan's rows of those truths added (point :data:`PUBLISHED`), stored as
    ``stored`` and summarised by ``keys`` into ``group``; nothing when the engines study's scan rows are not under
    the root."""
    published = _published_scans(job)
    if published is None:
        return
    truths = published_truths(published, int(job.cfg[f"{truths_key}_quick" if job.quick else truths_key]))
    job.progress(title, 0, 1)
    rows = sweep_rows(truths, job.p.scan, job.p.noise_sigma, points, job.progress)
    rows = pd.concat([rows, _published_rows(published, truths)], ignore_index=True)
    job.stored[stored] = rows
    job.res[group].update(keys(rows))


def pieces(job: Any) -> Pieces | None:
    """E218's sweep cut into its grid points (``pieces``), on the engines study's stored development truths; None
    when its scan rows are not under the root. A softer plate is guessed to take longer (the peg sinks and settles
    over more steps; the rigid point as the stiffest): only the order the points are submitted in. A quick run's
    points (one truth, about 2-6 s of CPU each) are one piece: a process's start-up would be a third of each."""
    published = _published_scans(job)
    if published is None:
        return None
    truths = published_truths(published, int(job.cfg["ex39_truths_quick" if job.quick else "ex39_truths"]))
    job.progress(f"explain: PyBullet's scans over {len(grid())} plate contacts (E218)", 0, 1)
    cuts = [tuple(range(len(grid())))] if job.quick else [(index,) for index in range(len(grid()))]
    calls = [(grid_points, (truths, cut, dict(job.p.scan), job.p.noise_sigma)) for cut in cuts]
    softness = [0.0 if np.isnan(k) else 1.0 / k for _, k, _ in grid()]
    return Pieces(calls, [sum(softness[i] for i in cut) for cut in cuts], functools.partial(combine, _published_rows(published, truths)))


def combine(mine: pd.DataFrame, parts: list[list[tuple[pd.DataFrame, float]]]) -> Filled:
    """The grid points' rows in grid order, then the published scan's rows (``mine``, :func:`_published_rows`),
    stored, and E218's keys."""
    rows = pd.concat([rows for part in parts for rows, _ in part], ignore_index=True)
    rows = pd.concat([rows, mine], ignore_index=True)
    return {"res": {GROUP: summary(rows)}, "stored": {STORED: rows}}


def run(job: Any) -> None:
    """The explain step (once the engines study is done): the sweep on its stored development truths, the stored
    rows and the keys; nothing when the engines study's scan rows are not under the root. The target sets its
    points aside as jobs of their own (``Explain.split(pieces)``)."""
    in_place(job, pieces)


__all__: Sequence[str] = ("run", "pieces", "combine", "grid_point", "grid_points", "summary", "sweep", "grid",
                          "label", "plate_contact", "published_truths", "point_rows", "scan_point", "point_keys",
                          "same_scans", "sweep_keys", "run_sweep", "STORED", "GROUP")
