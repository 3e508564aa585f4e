"""Table II's hinge row with the commit read as Table I says, a torque (E182 impulse, E183 0.25 s, E184 1 s).

Why: Table I gives the hinge's probe / action as "coast / torque"; ours commits a release speed, and ex25 argued
without a run that a torque "can only floor the probed miss". Declared rule (docs/decisions.md, "ex27"): the frozen
hinge config on MuJoCo with only the commit replaced by a torque for each declared duration (``hinge.torque``,
``hinge.sim_torque``), Blind-Bayes (k = 0) and Probe-Robust (k = 2, 5); the paper's Probe-Robust(5), implied
Probe-Robust(2), k2 / k5 ratio and Blind-Bayes inside ours, the ratio outside the stored release-speed run's, and
MuJoCo's torque matching its closed form (premise). Every key is computed by :func:`keys` from the stored rows, so
``verify`` recomputes them.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.stored import over_families, recompute_stored

#: The declared durations (s) of the torque, each its own rule (E182, E183, E184 in this order); 0: an impulse.
DURATIONS = {"impulse": 0.0, "d025": 0.25, "d1": 1.0}
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex27_torque_rows.parquet"
#: Premise: the largest |MuJoCo - closed form| of a torque commit allowed (rad; a quarter of sigma).
SCENE_TOLERANCE = 0.005
#: The premise's outcomes: per prior corner, the grid torques whose closed form lands nearest these angles (rad).
SCENE_TARGETS = (0.5, 1.0, 1.5)
#: The methods and budgets the rule reads (Blind-Bayes at k = 0, Probe-Robust at 2 and 5).
CELLS = (("blind_bayes", 0), ("probe_robust", 2), ("probe_robust", 5))


def part_keys(rows: pd.DataFrame, part: str) -> dict[str, float]:
    """One part's Blind-Bayes cell and Probe-Robust(2, 5) cells with the k2 / k5 ratio, each with its interval."""
    from probecommit.studies.explain.ex22_exact import _cell
    from probecommit.studies.explain.ex22_magnitude import part_cells

    sel = rows[rows["part"] == part]
    m, lo, hi = _cell(sel[sel["method"] == "blind_bayes"])
    return {f"{part}.bb": m, f"{part}.bb_lo": lo, f"{part}.bb_hi": hi,
            **part_cells(sel[sel["method"] == "probe_robust"], part)}


def condition_keys(rows: pd.DataFrame, cond: str, paper: dict[str, float], outside: bool) -> dict[str, float]:
    """One duration's keys: its cells, its premise and its declared rule's conditions."""
    out = part_keys(rows, cond)
    scene = rows[rows["part"] == f"scene.{cond}"]["realized"].to_numpy(float)
    worst = float(scene.max()) if len(scene) else float("nan")
    flags = {"k5_paper_inside": out[f"{cond}.k5_lo"] <= paper["k5"] <= out[f"{cond}.k5_hi"],
             "k2_paper_inside": out[f"{cond}.k2_lo"] <= paper["k2_implied"] <= out[f"{cond}.k2_hi"],
             "ratio_paper_inside": out[f"{cond}.ratio_lo"] <= paper["ratio_k2_k5"] <= out[f"{cond}.ratio_hi"],
             "bb_paper_inside": out[f"{cond}.bb_lo"] <= paper["bb"] <= out[f"{cond}.bb_hi"]}
    premise = bool(worst <= SCENE_TOLERANCE)
    out.update({f"{cond}.{name}": float(ok) for name, ok in flags.items()})
    out.update({f"{cond}.push_s": DURATIONS[cond], f"{cond}.scene_max_diff": worst,
                f"{cond}.premise_holds": float(premise), f"{cond}.scenes": float(len(scene)),
                f"{cond}.holds": float(premise and outside and all(flags.values()))})
    return out


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex27_torque`` from the stored rows (one function for the step and verify)."""
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    p5, p2 = value("tab:breadth.hinge.probe_robust"), implied_k2("hinge")
    paper = {"k5": p5, "k2_implied": p2, "ratio_k2_k5": p2 / p5, "bb": value("tab:breadth.hinge.blind_bayes")}
    out: dict[str, Any] = {f"paper.{name}": v for name, v in paper.items()}
    out.update(part_keys(rows, "stored"))
    outside = not out["stored.ratio_lo"] <= p2 / p5 <= out["stored.ratio_hi"]
    out.update({"stored_ratio_paper_outside": float(outside), "scene_tolerance": SCENE_TOLERANCE,
                "episodes": float(((rows["part"] == "stored") & (rows["k"] == 5)).sum())})
    for cond in DURATIONS:
        if (rows["part"] == cond).any():
            out.update(condition_keys(rows, cond, paper, outside))
    return out


def _cell_rows(episodes: pd.DataFrame, part: str) -> pd.DataFrame:
    keep = pd.Series(False, index=episodes.index)
    for method, k in CELLS:
        keep |= (episodes["method"] == method) & (episodes["k"] == k)
    ep = episodes[keep & (episodes["status"] == "ok")]
    return pd.DataFrame({"family": "hinge", "part": part, "method": ep["method"].to_numpy(str),
                         "instance_id": ep["instance_id"].to_numpy(), "repeat": ep["repeat"].to_numpy(np.int64),
                         "k": ep["k"].to_numpy(np.int64), "realized": ep["realized"].to_numpy(float)})


def scene_rows(cond: str) -> pd.DataFrame:
    """The premise's rows: |MuJoCo - closed form| of the torque commit at each prior corner and declared angle."""
    from probecommit.tasks.hinge.model import PRIOR_HIGH, PRIOR_LOW
    from probecommit.tasks.hinge.sim_torque import MujocoHingeTorqueSimulator
    from probecommit.tasks.hinge.torque import torque_angle, torque_grid

    push_s, rows = DURATIONS[cond], []
    grid, sim = torque_grid(push_s), MujocoHingeTorqueSimulator(push_s)
    for i, corner in enumerate(itertools.product(*zip(PRIOR_LOW, PRIOR_HIGH))):
        closed = torque_angle(grid, *corner, push_s)
        for j, angle in enumerate(SCENE_TARGETS):
            torque = float(grid[np.argmin(np.abs(closed - angle))])
            diff = abs(sim.push(*corner, torque) - float(torque_angle(torque, *corner, push_s)))
            rows.append({"family": "hinge", "part": f"scene.{cond}", "method": "scene", "instance_id": f"corner{i}",
                         "repeat": j, "k": -1, "realized": diff})
    return pd.DataFrame(rows)


def torque_episodes(cond: str, quick: bool) -> pd.DataFrame:
    """The frozen hinge config with the commit a torque of the declared duration (MuJoCo; quick: the closed form)."""
    from probecommit.runner import build
    from probecommit.runner.config import config_data, parse_config
    from probecommit.studies.explain.ex16_reach import _config, episodes_of
    from probecommit.tasks.hinge import sim_torque
    from probecommit.tasks.hinge.torque import torque_model

    data = config_data(_config("hinge", None, quick))
    data["methods"] = ["blind_bayes", "probe_robust"]
    config = parse_config(data)
    push_s, noise = DURATIONS[cond], config.simulator.noise_sigma
    scene = sim_torque.AnalyticHingeTorqueSimulator if quick else sim_torque.MujocoHingeTorqueSimulator
    return episodes_of(config, torque_model(build.build_model(config), push_s), lambda: scene(push_s, noise))


def family_rows(root: Path, family: str, quick: bool) -> pd.DataFrame:
    """The hinge's stored rows: the frozen run's cells, each duration's torque run and its premise."""
    from probecommit.studies.explain.ex8_blind import run_dir

    stored = pd.read_parquet(run_dir(root, family, quick) / "episodes.parquet")
    parts = [_cell_rows(stored, "stored")]
    for cond in DURATIONS:
        parts += [_cell_rows(torque_episodes(cond, quick), cond), scene_rows(cond)]
    return pd.concat(parts, ignore_index=True)


def run(root: Path, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, when the breadth study's hinge run is under ``root``."""
    return over_families(root, quick, ("hinge",), family_rows, keys)


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``)."""
    return recompute_stored(folder, published, STORED, keys)
