"""Table II's probed cells with "uniform random" probes read over the probe interval (E174 push1d, E175 hinge).

Why: Sec. IV-A says "The robot's probes are uniform random unless stated", and Table I names each family's probe kind
("pulse", "coast") but no set of magnitudes. Ours draws each probe from a three-point grid with replacement; the other
reading of the same words is a probe uniform over an interval. Every earlier grid (E124, E125, E158) kept three points,
and our miss falls from k = 2 to k = 5 by about averaging's sqrt(5/2) where the paper's falls by about 2. Declared rule
(docs/decisions.md, "ex25"): the frozen config on its closed-form scene with 201 evenly spaced probes over the frozen
grid's span, everything else frozen, Probe-Robust at k = 2 and 5; both of the paper's curve points and its k2 / k5
ratio inside ours, and the ratio outside the frozen grid's on the same scene. Every key is computed by :func:`keys`
from the stored rows, so ``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.stored import over_families, recompute_stored

#: The families (E174, E175 in this order): the reruns' engine (None: the frozen run's own, already closed form) and
#: the premise's tolerance (relative: the frozen grid on that scene against the stored Probe-Robust(5) cell).
FAMILIES = {"push1d": (None, 1e-9), "hinge": ("analytic", 0.05)}
#: Points of the interval draw: evenly spaced from the frozen grid's smallest to its largest magnitude (1 % steps).
POINTS = 201
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex25_uniform_rows.parquet"
#: The budgets of the paper's curve the rule reads.
BUDGETS = (2, 5)
#: The parts of each family's rows: the frozen run, the frozen grid rerun, and the declared conditions: the interval
#: draw (E174/E175) and the frozen grid's two ends (E176/E177).
PARTS = ("stored", "grid", "interval", "ends")
#: The declared conditions, each tested by its own rule.
CONDITIONS = ("interval", "ends")


def ends_grid(frozen: np.ndarray) -> tuple[float, ...]:
    """The frozen grid's smallest and largest magnitude (E176/E177: the middle point dropped)."""
    frozen = np.asarray(frozen, float).ravel()
    return float(frozen.min()), float(frozen.max())


def interval_grid(frozen: np.ndarray, points: int = POINTS) -> tuple[float, ...]:
    """``points`` magnitudes evenly spaced over the frozen grid's span (its ends included), rounded to 1e-10."""
    frozen = np.asarray(frozen, float).ravel()
    return tuple(float(round(u, 10)) for u in np.linspace(frozen.min(), frozen.max(), points))


def family_keys(rows: pd.DataFrame, family: str) -> dict[str, float]:
    """One family's keys: each part's cells and k2 / k5 ratio with intervals, the premise and each declared rule
    (E174/E175 on ``interval``, E176/E177 on ``ends``)."""
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.explain.ex22_magnitude import part_cells
    from probecommit.studies.paper_values import value

    p5, p2 = value(f"tab:breadth.{family}.probe_robust"), implied_k2(family)
    out: dict[str, float] = {"paper.k5": p5, "paper.k2_implied": p2, "paper.ratio_k2_k5": p2 / p5}
    present = [part for part in PARTS if (rows["part"] == part).any()]
    for part in present:
        out.update(part_cells(rows[rows["part"] == part], part))
    tolerance = FAMILIES[family][1]
    diff = abs(out["grid.k5"] - out["stored.k5"]) / out["stored.k5"]
    outside = not out["grid.ratio_lo"] <= p2 / p5 <= out["grid.ratio_hi"]
    out.update({"premise_rel_diff": diff, "premise_tolerance": tolerance, "premise_holds": float(diff <= tolerance),
                "grid_ratio_paper_outside": float(outside),
                "episodes": float(len(rows[(rows["part"] == "grid") & (rows["k"] == BUDGETS[-1])]))})
    for part in CONDITIONS:
        if part not in present:
            continue
        flags = {"k5_paper_inside": out[f"{part}.k5_lo"] <= p5 <= out[f"{part}.k5_hi"],
                 "k2_paper_inside": out[f"{part}.k2_lo"] <= p2 <= out[f"{part}.k2_hi"],
                 "ratio_paper_inside": out[f"{part}.ratio_lo"] <= p2 / p5 <= out[f"{part}.ratio_hi"]}
        out.update({f"{part}.{name}": float(ok) for name, ok in flags.items()})
        out[f"{part}.holds"] = float(diff <= tolerance and outside and all(flags.values()))
    return out


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex25_uniform`` from the stored rows (one function for the step and verify)."""
    out: dict[str, Any] = {"points": float(POINTS)}
    for family in FAMILIES:
        sel = rows[rows["family"] == family]
        if len(sel):
            out.update({f"{family}.{name}": v for name, v in family_keys(sel, family).items()})
    return out


def _probe_rows(episodes: pd.DataFrame, family: str, part: str) -> pd.DataFrame:
    ep = episodes[(episodes["method"] == "probe_robust") & episodes["k"].isin(BUDGETS) & (episodes["status"] == "ok")]
    return pd.DataFrame({"family": family, "part": part, "instance_id": ep["instance_id"].to_numpy(),
                         "repeat": ep["repeat"].to_numpy(np.int64), "k": ep["k"].to_numpy(np.int64),
                         "realized": ep["realized"].to_numpy(float)})


def family_rows(root: Path, family: str, quick: bool) -> pd.DataFrame:
    """One family's stored rows: the frozen run, the frozen grid on the reruns' scene, the interval draw, the ends."""
    from probecommit.runner.build import build_model
    from probecommit.studies.explain.ex8_blind import run_dir
    from probecommit.studies.explain.ex16_reach import _config, episodes_with_grid

    config = _config(family, FAMILIES[family][0], quick)
    frozen = np.asarray(build_model(config).probe_grid, float)[:, 0]
    stored = pd.read_parquet(run_dir(root, family, quick) / "episodes.parquet")
    return pd.concat([_probe_rows(stored, family, "stored"),
                      _probe_rows(episodes_with_grid(config, None), family, "grid"),
                      _probe_rows(episodes_with_grid(config, interval_grid(frozen)), family, "interval"),
                      _probe_rows(episodes_with_grid(config, ends_grid(frozen)), family, "ends")],
                     ignore_index=True)


def run(root: Path, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, for the families whose breadth runs are under ``root``."""
    return over_families(root, quick, FAMILIES, family_rows, keys)


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``)."""
    return recompute_stored(folder, published, STORED, keys)
