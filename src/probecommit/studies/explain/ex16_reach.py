"""Table II's probed cells with probes that reach the commit regime (E124 hinge, E125 push1d).

Why: Table I names each family's probe ("coast", "pulse") but not its magnitudes; ours were chosen
from physical sense and read the scene far below the regime the commit acts in (at the prior's
centre the hinge's three coasts stop at 0.07-0.48 rad against targets 0.5-1.5 rad, push1d's pulses
slide 0.10-0.63 m against 0.5-1.5 m). The paper's one stated probe grid, insertion's taps, spans
the whole decision domain. The paper's probed cells also gain more from k = 2 to k = 5 than ours
(its k = 2 point follows from its printed k = 5 cell and five-below price). Cause under test: the
probe grid's reach. One declared alternative per family (docs/decisions.md, "ex16"): three probes
whose noise-free outcome at the prior box's centre is each frozen target, everything else frozen,
Probe-Robust at k = 2 and 5, on the family's closed-form scene. Every key is computed by
:func:`keys` from the stored rows, so ``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.stored import over_families, recompute_stored

#: The families (E124, E125 in this order): the declared reach grid (rounded to 0.01, docs/decisions.md, "ex16"),
#: the engine the reruns use (None: the frozen run's own, already closed form) and the premise's tolerance
#: (relative: the analytic scene against the stored MuJoCo cell; push1d's rerun is the stored run itself).
FAMILIES = {"hinge": ((1.54, 2.38, 3.10), "analytic", 0.05), "push1d": ((2.60, 4.07, 5.36), None, 1e-9)}
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex16_reach_rows.parquet"
#: The budgets of the paper's curve the rule reads (Probe-Robust at k = 2 and 5).
BUDGETS = (2, 5)
#: Cluster bootstrap as Table II's cells (``studies.breadth.run_breadth``'s defaults).
RESAMPLES, SEED = 2000, 0
#: T01's price unit per family, in the miss's units (the paper prints cm for the pushes, rad for the hinge).
PRICE_UNIT = {"hinge": 1.0, "push1d": 0.01}


def reach_grid(model: Any, targets: tuple[float, ...], digits: int = 2) -> tuple[float, ...]:
    """The probes whose noise-free outcome at the prior box's centre equals each target (bisection on the
    model's monotone outcome), rounded to ``digits``: the declared condition's grid."""
    centre = (np.asarray(model.prior_low, float) + np.asarray(model.prior_high, float)) / 2
    outcome = lambda u: float(model.predict(np.array([u]), centre[None, None, :])[0, 0, 0])  # noqa: E731
    out = []
    for target in targets:
        lo, hi = 1e-6, 1.0
        while outcome(hi) < target:
            hi *= 2
        for _ in range(200):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if outcome(mid) < target else (lo, mid)
        out.append(round((lo + hi) / 2, digits))
    return tuple(out)


def implied_k2(family: str) -> float:
    """The paper's Probe-Robust(2), fixed by its printed Probe-Robust(5) and five-below price: ``m5 + 3 p``
    (``five_below = (m2 - m5) / 3`` whenever ``(m0 - m5) / 5`` is larger, as it is for every m0 above the
    printed Blind-Bayes cell; docs/decisions.md, "ex16")."""
    from probecommit.studies.paper_values import value

    return value(f"tab:breadth.{family}.probe_robust") + 3 * value(f"T01-pricing.five_below.{family}") * PRICE_UNIT[family]


def _cell(rows: pd.DataFrame) -> tuple[float, float, float]:
    from probecommit.audit.stats import cluster_bootstrap_mean

    ci = cluster_bootstrap_mean(rows["realized"].to_numpy(float), rows["instance_id"].to_numpy(), resamples=RESAMPLES,
                                seed=SEED)
    return float(ci.estimate), float(ci.lo), float(ci.hi)


def family_keys(rows: pd.DataFrame, family: str) -> dict[str, float]:
    """One family's keys from its stored rows (``part``: ``stored`` = the frozen run's Probe-Robust episodes,
    ``scene`` = the frozen grid rerun on the reach condition's scene, ``reach`` = the reach grid)."""
    from probecommit.studies.paper_values import value

    out: dict[str, float] = {}
    for part in ("stored", "scene", "reach"):
        for k in BUDGETS:
            m, lo, hi = _cell(rows[(rows["part"] == part) & (rows["k"] == k)])
            out.update({f"{part}.k{k}": m, f"{part}.k{k}_lo": lo, f"{part}.k{k}_hi": hi})
        out[f"{part}.ratio_k2_k5"] = out[f"{part}.k2"] / out[f"{part}.k5"]
    tol = FAMILIES[family][2]
    diff = abs(out["scene.k5"] - out["stored.k5"]) / out["stored.k5"]
    p5, p2 = value(f"tab:breadth.{family}.probe_robust"), implied_k2(family)
    in5 = out["reach.k5_lo"] <= p5 <= out["reach.k5_hi"]
    in2 = out["reach.k2_lo"] <= p2 <= out["reach.k2_hi"]
    out.update({"grid.0": FAMILIES[family][0][0], "grid.1": FAMILIES[family][0][1], "grid.2": FAMILIES[family][0][2],
                "episodes": float(((rows["part"] == "reach") & (rows["k"] == BUDGETS[-1])).sum()),
                "premise_rel_diff": diff, "premise_tolerance": tol, "premise_holds": float(diff <= tol),
                "paper.k5": p5, "paper.k2_implied": p2, "paper.ratio_k2_k5": p2 / p5,
                "reach.k5_paper_inside": float(in5), "reach.k2_paper_inside": float(in2),
                "holds": float(diff <= tol and in5 and in2), "resamples": float(RESAMPLES)})
    return out


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex16_reach`` from the stored rows (one function for the step and verify)."""
    return {f"{family}.{k}": v for family, part in rows.groupby("family", sort=False)
            for k, v in family_keys(part, str(family)).items()}


def _probe_rows(episodes: pd.DataFrame, family: str, part: str) -> pd.DataFrame:
    ep = episodes[(episodes["method"] == "probe_robust") & episodes["k"].isin(BUDGETS) & (episodes["status"] == "ok")]
    return pd.DataFrame({"family": family, "part": part, "instance_id": ep["instance_id"].to_numpy(),
                         "repeat": ep["repeat"].to_numpy(np.int64), "k": ep["k"].to_numpy(np.int64),
                         "target": ep["ctx_target"].to_numpy(float) if "ctx_target" in ep else np.nan,
                         "realized": ep["realized"].to_numpy(float)})


def _config(family: str, engine: str | None, quick: bool) -> Any:
    """The frozen config (its quick version in a quick run) with Probe-Robust only, budgets 2 and 5, ``engine``."""
    from probecommit.runner.config import config_data, parse_config
    from probecommit.studies.breadth import paper_config, quick_config

    base = paper_config(family)
    data = config_data(quick_config(base) if quick else base)
    data["methods"] = ["probe_robust"]
    data["probes"] = {**data["probes"], "budget": BUDGETS[-1], "budgets": list(BUDGETS)}
    if engine is not None:
        data["simulator"] = {**data["simulator"], "engine": engine}
    return parse_config(data)


def episodes_with_grid(config: Any, grid: tuple[float, ...] | None) -> pd.DataFrame:
    """The episodes of ``config`` with the model's probe grid replaced by ``grid`` (None: the frozen grid), computed
    in memory unit by unit (the run's own seeding: per instance and repeat, so units do not change a number)."""
    from probecommit.runner import build

    model = build.build_model(config)
    if grid is not None:  # the same model with another probe grid (a class attribute of every family)
        variant = type(f"{type(model).__name__}Reach", (type(model),), {"probe_grid": np.asarray(grid, float)[:, None]})
        model = variant(**{f: getattr(model, f) for f in model.__dataclass_fields__})
    return episodes_of(config, model)


def episodes_of(config: Any, model: Any, simulator: Any = None) -> pd.DataFrame:
    """The episodes of ``config`` run with ``model`` (and each unit's simulator from the factory ``simulator``; None:
    the config's engine), in memory unit by unit (E124's and ex27's reruns; the run's own seeding)."""
    from probecommit.runner import build
    from probecommit.runner.instances import draw_instances
    from probecommit.runner.study import RunParts, compute_unit, unit_names

    parts = RunParts(config, model, build.build_filter(model, config.belief), build.config_executors(config, model),
                     simulator)
    instances = draw_instances(config, model)
    frames = []
    for unit, rows in unit_names(len(instances), config.unit_instances):
        frames.append(compute_unit(parts, instances.iloc[rows].reset_index(drop=True), unit)[1]["episodes"].to_pandas())
    episodes = pd.concat(frames, ignore_index=True)
    return episodes.merge(instances[["instance_id", "ctx_target"]], on="instance_id", how="left") \
        if "ctx_target" not in episodes and "ctx_target" in instances else episodes


def family_rows(root: Path, family: str, quick: bool) -> pd.DataFrame:
    """One family's stored rows: the frozen run's cells, the frozen grid on the reruns' scene, the reach grid."""
    from probecommit.studies.explain.ex8_blind import run_dir

    grid, engine, _ = FAMILIES[family]
    stored = pd.read_parquet(run_dir(root, family, quick) / "episodes.parquet")
    instances = pd.read_parquet(run_dir(root, family, quick) / "instances.parquet")
    if "ctx_target" not in stored:
        stored = stored.merge(instances[["instance_id", "ctx_target"]], on="instance_id", how="left")
    config = _config(family, engine, quick)
    return pd.concat([_probe_rows(stored, family, "stored"),
                      _probe_rows(episodes_with_grid(config, None), family, "scene"),
                      _probe_rows(episodes_with_grid(config, grid), family, "reach")], ignore_index=True)


def run(root: Path, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, for the families whose breadth runs are under ``root``."""
    return over_families(root, quick, FAMILIES, family_rows, keys)


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``)."""
    return recompute_stored(folder, published, STORED, keys)
