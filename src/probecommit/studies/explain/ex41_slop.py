"""PyBullet's capture window against the contact slop (E228; ex41, issue #36; rule declared in
``docs/decisions.md``, "ex41", before the sweep's numbers were computed).

Why: the paper's PyBullet captures the peg over 1.21 x w(c) with an SD of 0.69 of that ratio across the 24
development truths, ours over 1.000 x w(c) with SD 0.0002 (T18); a compliant plate (E218) gives the mean but not the
spread. Of the PyBullet settings the prototypes moved one at a time (timestep, ERP, split impulse, margin, breaking
threshold, the drive's force limit), only ``contactSlop``, the penetration Bullet leaves uncorrected, made the
per-truth windows differ; ours (1e-6 m) is below PyBullet's default (1e-5 m). This step sweeps it over the declared
grid, runs the engines study's two scans unchanged at each point on its 24 development truths (ex39's point
function), and picks the point by the capture ratio the paper reports; E228 then asks whether, there, the tap
boundary still matches the paper's, the per-truth ratio spreads as the paper's does, and the mean is the paper's.
Every key is :func:`summary` of the stored scan rows (:data:`STORED`), so verify recomputes them.
"""

from __future__ import annotations

from typing import Any, Sequence

import pandas as pd

from probecommit.engines.pybullet import MM_PHYSICS
from probecommit.studies.explain import ex39_pybullet as ex39
from probecommit.studies.paper_values import value as paper_value

#: The stored scan rows (``studies.engines.scan_rows`` per grid point, and the published scan), beside results.json.
STORED = "ex41_slop_rows.parquet"
#: Result group.
GROUP = "ex41_slop"
#: The declared grid (docs/decisions.md, "ex41"): ``contactSlop`` (m); ours first, then PyBullet's default.
SLOP = (1e-6, 1e-5, 3e-5, 1e-4, 2e-4, 3e-4)
#: A quick run's points (ours and PyBullet's default).
QUICK = 2
#: E228's part (c): the mean ratio within T18's tolerance of the paper's.
RATIO_TOLERANCE = 0.1


def label(slop: float) -> str:
    """A grid point's name in keys: ``slop<micrometres>um`` (``slop1um``, ``slop300um``)."""
    return f"slop{round(slop * 1e6):d}um"


#: Our published scene's point (compared with the published scan).
OURS = label(SLOP[0])


def grid() -> list[tuple[str, float]]:
    """The declared points in grid order: (name, slop)."""
    return [(label(s), s) for s in SLOP]


def physics(slop: float) -> dict[str, Any]:
    """The engine parameters at a grid point: our published ``MM_PHYSICS`` with only ``contactSlop`` replaced."""
    return {**MM_PHYSICS, "contactSlop": float(slop)}


def sweep(truths: pd.DataFrame, scan: dict[str, float], noise_sigma: float, points: Sequence[str] | None = None,
          progress: Any = None) -> pd.DataFrame:
    """The grid's scan rows (columns ``point, index, slop`` added), the points named in ``points`` only when given."""
    step = progress or (lambda *a: None)
    parts = []
    for index, (name, slop) in enumerate(grid()):
        if points is not None and name not in points:
            continue
        rows, cpu = ex39.scan_point(truths, scan, noise_sigma, physics=physics(slop))
        step(f"explain: E228 point {name} ({cpu:.0f} s CPU)", index + 1, len(grid()))
        parts.append(rows.assign(point=name, index=index, slop=slop))
    return pd.concat(parts, ignore_index=True)


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """E228's keys from the stored rows: ex39's sweep keys over the slop (every point, the point nearest the paper's
    ratio, parts (a) and (b), ``slop1um_equals_published``), part (c) ``mean_ok`` and ``holds``."""
    out = ex39.sweep_keys(rows, ("slop",), OURS)
    paper_ratio = paper_value("T18-engine-scans.pybullet_ratio")
    out["ratio_tolerance"] = RATIO_TOLERANCE
    out["mean_ok"] = int(abs(out["chosen.ratio_mean"] - paper_ratio) <= RATIO_TOLERANCE)
    out["holds"] = int(out["boundary_ok"] and out["spread_ok"] and out["mean_ok"])
    return out


def run(job: Any) -> None:
    """The explain step (set aside once the engines study is done): the sweep on the engines study's stored
    development truths (a quick run: its first :data:`QUICK` points), the stored rows and the keys."""
    points = [name for name, _ in grid()[:QUICK]] if job.quick else None
    ex39.run_sweep(job, "ex41_truths", f"explain: PyBullet's scans over {len(grid())} contact slops (E228)", sweep,
                   STORED, GROUP, summary, points)


__all__: Sequence[str] = ("run", "summary", "sweep", "grid", "label", "physics", "STORED", "GROUP", "SLOP", "OURS")
