"""Table II's blind cells over redrawn truth sets (E75..E78).

Why: the paper's pushing and darts rows use fixed truth sets it does not report (3 x 6, 6 x 3;
push1d's 81 instances are 27 truths x 3 targets, as ours), and ours are our own choice. A blind
commit reads no probe, so its cell is the miss of a fixed action per target (Blind-Robust: each
seed's stored action) averaged over the truths: it depends on which few truths were taken. The
truth set is redrawn uniformly over our prior box (our size, our targets, the frozen blind
actions), each truth's miss from the family's model, and the paper's blind cells are compared with
the redraws' central 95 %; a premise checks that the model gives the engine's blind cells on our
own truths (docs/decisions.md, "ex8"). No engine run; verify recomputes everything (seeded) from
the stored blind episodes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

#: The families whose printed blind cells differ, and those cells (Table II).
FAMILIES = {"push1d": ("blind_bayes",), "push2d": ("blind_bayes", "blind_robust"),
            "push2d_pybullet": ("blind_bayes",), "darts": ("blind_bayes", "blind_robust")}
ARMS = ("blind_bayes", "blind_robust")
#: The stored blind episodes (every family's, with truth and target), beside results.json.
STORED = "ex8_blind_episodes.parquet"
#: Redraw seed, premise tolerance (relative) and the central interval (declared).
SEED, PREMISE, CENTRAL = 3601, 0.02, (2.5, 97.5)
#: Redrawn truths per block of :func:`redraw_cells`' loss matrix.
REDRAW_BLOCK = 4096


def run_dir(root: Path, family: str, quick: bool = False) -> Path:
    """The breadth study's run of ``family`` under ``root`` (its quick version's in a quick run)."""
    from probecommit.studies.breadth import paper_config, quick_config

    config = paper_config(family)
    return Path(root) / "breadth" / "runs" / (quick_config(config) if quick else config).name


def blind_rows(root: Path, family: str, quick: bool = False) -> pd.DataFrame:
    """The frozen run's blind episodes (status ok) with each instance's truth and target."""
    run = run_dir(root, family, quick)
    episodes = pd.read_parquet(run / "episodes.parquet")
    episodes = episodes[episodes["method"].isin(ARMS) & (episodes["status"] == "ok")]
    keep = ["instance_id", "repeat", "method", "realized", *[c for c in episodes.columns if c.startswith("action")]]
    instances = pd.read_parquet(run / "instances.parquet")
    cols = ["instance_id", *[c for c in instances.columns if c.startswith(("true_", "ctx_"))]]
    return episodes[keep].merge(instances[cols], on="instance_id", how="left").assign(family=family)


def _model(family: str) -> Any:
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config

    return build_model(paper_config(family))


def _parts(rows: pd.DataFrame, model: Any) -> tuple[list[str], list[str], list[str]]:
    actions = sorted(c for c in rows.columns if c.startswith("action") and rows[c].notna().any())
    return actions, [f"true_{n}" for n in model.latent_names], sorted(c for c in rows.columns if c.startswith("ctx_")
                                                                       and rows[c].notna().any())


def model_cell(rows: pd.DataFrame, model: Any) -> float:
    """Mean model miss of each stored episode's own action at its own truth and target (the premise)."""
    actions, truths, ctx = _parts(rows, model)
    misses = []
    for _, part in rows.groupby(ctx, sort=True):
        loss = model.loss(part[actions].to_numpy(float), part[truths].to_numpy(float), part[ctx].iloc[0].to_numpy(float))
        misses.append(np.diagonal(np.asarray(loss, dtype=float)))
    return float(np.concatenate(misses).mean())


def redraw_cells(rows: pd.DataFrame, model: Any, n_truths: int, draws: int, seed: int) -> np.ndarray:
    """``[draws]`` cells of one blind arm: truth sets of ``n_truths`` drawn uniformly over the prior box, each
    truth's miss averaged over the arm's stored actions at each target, then over truths and targets."""
    actions, _, ctx = _parts(rows, model)
    low, high = np.asarray(model.prior_low, float), np.asarray(model.prior_high, float)
    theta = low + (high - low) * np.random.default_rng(seed).random((draws * n_truths, low.size))
    per_target = []
    # A block of truths at a time (issue 42: the whole [actions, truths] matrix and its temporaries added 300 MB to
    # the explain process). Each truth's column is the same numbers summed in the same order in any block of at
    # least two columns (one column alone would be summed pairwise), so the cells are the whole matrix's bits.
    blocks = min(-(-len(theta) // REDRAW_BLOCK), max(1, len(theta) // 2))
    edges = np.linspace(0, len(theta), blocks + 1).round().astype(int)
    for _, part in rows.groupby(ctx, sort=True):
        acts, target = part[actions].to_numpy(float), part[ctx].iloc[0].to_numpy(float)
        per_target.append(np.concatenate([np.asarray(model.loss(acts, theta[a:b], target), float).mean(axis=0)
                                          for a, b in zip(edges[:-1], edges[1:])]))  # each stored action weighs the same
    return np.mean(per_target, axis=0).reshape(draws, n_truths).mean(axis=1)


def family_keys(rows: pd.DataFrame, family: str, draws: int) -> dict[str, float]:
    """One family's keys (``<family>.*``) from its stored blind episodes."""
    from probecommit.studies.paper_values import value

    model = _model(family)
    _, truths, ctx = _parts(rows, model)
    n_truths = int(rows[truths].drop_duplicates().shape[0])
    out: dict[str, float] = {"n_truths": float(n_truths), "targets": float(rows[ctx].drop_duplicates().shape[0]),
                             "draws": float(draws)}
    cells, premise, inside = {}, True, 0
    for i, arm in enumerate(ARMS):
        part = rows[rows["method"] == arm]
        stored, computed = float(part["realized"].mean()), model_cell(part, model)
        cells[arm] = redraw_cells(part, model, n_truths, draws, SEED + i)
        lo, hi = np.percentile(cells[arm], CENTRAL)
        out.update({f"{arm}.stored": stored, f"{arm}.model_frozen": computed,
                    f"{arm}.premise_rel_diff": abs(computed - stored) / stored, f"{arm}.draws.mean":
                    float(cells[arm].mean()), f"{arm}.draws.p025": float(lo), f"{arm}.draws.p975": float(hi)})
        premise &= abs(computed - stored) <= PREMISE * stored
        if arm in FAMILIES[family]:
            paper = value(f"tab:breadth.{family}.{arm}")
            out[f"{arm}.paper_inside"] = float(lo <= paper <= hi)
            inside += int(lo <= paper <= hi)
    ratio = cells["blind_robust"] / cells["blind_bayes"]
    rlo, rhi = np.percentile(ratio, CENTRAL)
    out.update({"ratio.draws.p025": float(rlo), "ratio.draws.p975": float(rhi),
                "premise_holds": float(premise), "cells": float(len(FAMILIES[family])), "cells_inside": float(inside)})
    if len(FAMILIES[family]) == 2:
        paper_ratio = value(f"tab:breadth.{family}.blind_robust") / value(f"tab:breadth.{family}.blind_bayes")
        out["ratio.paper"], out["ratio.paper_inside"] = paper_ratio, float(rlo <= paper_ratio <= rhi)
    return out


def keys(stored: pd.DataFrame, draws: int) -> dict[str, Any]:
    """Keys of ``explain:results.ex8_blind`` from the stored blind episodes (one function for the step and verify)."""
    out: dict[str, Any] = {}
    for family, rows in stored.groupby("family", sort=False):
        out.update({f"{family}.{k}": v for k, v in family_keys(rows.drop(columns="family"), str(family), draws).items()})
    return out


def run(root: Path, draws: int, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, for the families whose breadth runs are under ``root``."""
    present = [f for f in FAMILIES if (run_dir(root, f, quick) / "episodes.parquet").is_file()]
    if not present:
        return {}, pd.DataFrame()
    stored = pd.concat([blind_rows(root, f, quick) for f in present], ignore_index=True)
    return keys(stored, draws), stored


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``), with the published draw count."""
    if not (folder / STORED).is_file() or not published:
        return {}
    draws = int(next(v for k, v in published.items() if k.endswith(".draws")))
    return keys(pd.read_parquet(folder / STORED), draws)
