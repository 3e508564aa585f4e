"""Table II's probed cells against the floor the action grid alone puts on the miss (E196 push1d, E197 hinge).

Why: a one-shot commit on a finite grid misses even under the true parameters, and the paper reports no action grid
for these families (only insertion's 0.5 mm aims). If our grid's floor were a material part of our Probe-Robust(5)
miss, a finer grid (the paper's, unreported) would lower the two probed cells that sit above the paper's. Declared
rule (docs/decisions.md, "ex32"): per instance the floor ``f_i`` (the best grid action's model miss at the truth) and
the grid's half step at the truth ``h_i`` (half the outcome step between the two grid actions bracketing the target);
the grid is the cause if the mean floor over the stored Probe-Robust(5) episodes is at least our cell minus the
paper's, AND the paper's Probe-Robust(5) and implied Probe-Robust(2) lie inside the intervals of the floor-removed
miss ``max(realized - h_i, 0)``. push2d's floor is published beside (its paper cell is above ours). No engine, no
belief, no rerun: every key is computed by :func:`keys` from the stored rows, so ``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.stored import over_families, recompute_stored

#: The families (E196, E197 in this order; push2d beside, no rule) and the premise's tolerance (relative: the
#: model's miss of the stored Probe-Robust(5) actions at the truth against the stored cell; E156/E157's premise (a)).
FAMILIES = {"push1d": 1e-6, "hinge": 0.05, "push2d": None}
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex32_floor_rows.parquet"
#: The budgets of the paper's curve the rule reads (Probe-Robust at k = 2 and 5).
BUDGETS = (2, 5)


def floor_and_half_step(model: Any, truth: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """The grid's floor at one instance (the least model miss over the frozen action grid at the truth ``truth[d]``
    and target ``target[c]``) and, for a coast (an outcome rising with a scalar action), its half step at the truth:
    half the outcome step between the two adjacent grid actions that bracket the target, the floor itself where no
    pair brackets it (the target beyond the grid's reach). NaN half step for a 2-D action (push2d)."""
    grid = np.asarray(model.action_grid, float)
    losses = np.asarray(model.loss(grid, truth[None, :], target))[:, 0]
    floor = float(np.min(losses))
    if not hasattr(model, "commit_outcome"):
        return floor, float("nan")
    d = np.asarray(model.commit_outcome(grid[:, 0], *truth), float)
    j = int(np.searchsorted(d, float(target[0]), side="right"))
    if j <= 0 or j >= len(d):
        return floor, floor
    return floor, float((d[j] - d[j - 1]) / 2 / model.margin)


def family_rows(root: Path, family: str, quick: bool) -> pd.DataFrame:
    """One family's stored rows: each stored Probe-Robust episode at k = 2 and 5 with its realized miss, the model's
    miss of its stored action at the truth, and its instance's floor and half step (``floor_and_half_step``)."""
    from probecommit.studies.explain.ex22_exact import model_miss, probed_episodes

    model, _, episodes = probed_episodes(root, family, quick)
    truth = episodes[[f"true_{n}" for n in model.latent_names]].to_numpy(float)
    targets = episodes[[c for c in episodes.columns if c.startswith("ctx_")]].to_numpy(float)
    first = ~episodes["instance_id"].duplicated().to_numpy()
    per = {iid: floor_and_half_step(model, truth[i], targets[i])
           for i, iid in zip(np.flatnonzero(first), episodes["instance_id"].to_numpy()[first])}
    action_cols = ["action"] if "action" in episodes else [c for c in episodes.columns if c.startswith("action_")]
    actions = episodes[action_cols].to_numpy(float)
    return pd.DataFrame({"family": family, "instance_id": episodes["instance_id"].to_numpy(),
                         "repeat": episodes["repeat"].to_numpy(np.int64), "k": episodes["k"].to_numpy(np.int64),
                         "realized": episodes["realized"].to_numpy(float),
                         "model": model_miss(model, actions, truth, targets),
                         "floor": [per[i][0] for i in episodes["instance_id"]],
                         "half": [per[i][1] for i in episodes["instance_id"]]})


def _cell_of(rows: pd.DataFrame, values: np.ndarray) -> tuple[float, float, float]:
    """Table II's cell (mean, 95 % cluster-bootstrap interval over instances) of ``values`` over ``rows``."""
    from probecommit.studies.explain.ex22_exact import _cell

    return _cell(pd.DataFrame({"realized": values, "instance_id": rows["instance_id"].to_numpy()}))


def family_keys(rows: pd.DataFrame, family: str) -> dict[str, float]:
    """One family's keys from its stored rows (the rule of docs/decisions.md, "ex32", for push1d and the hinge;
    the floor and its share only for push2d)."""
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    out: dict[str, float] = {}
    for k in BUDGETS:
        part = rows[rows["k"] == k]
        realized = part["realized"].to_numpy(float)
        cells = {"stored": realized} | ({"floor": part["floor"].to_numpy(float)} if k == BUDGETS[-1] else {})
        if FAMILIES[family] is not None:
            cells["removed"] = np.maximum(realized - part["half"].to_numpy(float), 0.0)
        for name, values in cells.items():
            m, lo, hi = _cell_of(part, values)
            out.update({f"{name}.k{k}": m, f"{name}.k{k}_lo": lo, f"{name}.k{k}_hi": hi})
    k5 = rows[rows["k"] == BUDGETS[-1]]
    p5 = value(f"tab:breadth.{family}.probe_robust")
    out.update({"episodes": float(len(k5)), "floor_share": out["floor.k5"] / out["stored.k5"], "paper.k5": p5,
                "floor_max": float(k5["floor"].max())})
    if FAMILIES[family] is None:
        return out
    p2 = implied_k2(family)
    premise = abs(float(k5["model"].mean()) - out["stored.k5"]) / out["stored.k5"]
    gap = out["stored.k5"] - p5
    in5 = out["removed.k5_lo"] <= p5 <= out["removed.k5_hi"]
    in2 = out["removed.k2_lo"] <= p2 <= out["removed.k2_hi"]
    out.update({"paper.k2_implied": p2, "gap": gap, "floor_covers_gap": float(out["floor.k5"] >= gap),
                "half_mean": float(k5["half"].mean()), "half_max": float(k5["half"].max()),
                "premise_model_rel_diff": premise, "premise_model_tolerance": FAMILIES[family],
                "premise_holds": float(premise <= FAMILIES[family]),
                "removed.k5_paper_inside": float(in5), "removed.k2_paper_inside": float(in2)})
    out["holds"] = float(out["premise_holds"] == 1 and out["floor_covers_gap"] == 1 and in5 and in2)
    return out


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex32_floor`` from the stored rows (one function for the step and verify)."""
    return {f"{family}.{k}": v for family, part in rows.groupby("family", sort=False)
            for k, v in family_keys(part, str(family)).items()}


def run(root: Path, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, for the families whose breadth runs are under ``root``."""
    return over_families(root, quick, FAMILIES, family_rows, keys, files=("episodes.parquet", "instances.parquet"))


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``)."""
    return recompute_stored(folder, published, STORED, keys)
