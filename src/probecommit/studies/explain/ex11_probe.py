"""Table II's Probe-Robust cells over redrawn truth sets (E94 hinge, E95 2-D push MuJoCo).

Why: the paper's hinge and pushing rows use fixed truth sets it does not report ("fixed truth and
target sets (3 x 6, 6 x 3, 6 x 3) with random seeds"); ours are our choice. E75..E78 redrew the
blind cells with the model alone; a Probe-Robust cell reads probes, so it needs probe episodes at
the redrawn truths. One pool of truths per family, drawn uniformly over the frozen prior box, is
run once (Probe-Robust at k = 5 only, our targets and seed count; the hinge on its closed-form
scene, the 2-D push on its frozen MuJoCo engine), and truth sets of our size are redrawn from the
pool. A premise checks that the pool's scene gives our stored cell on our own truths
(docs/decisions.md, "ex11"). Every key is computed by :func:`keys` from the stored rows, so
``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

#: The families redrawn (E94, E95 in this order): pool size, pool engine (None: the frozen run's own).
FAMILIES = {"hinge": (36, "analytic"), "push2d": (18, None)}
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex11_probe_rows.parquet"
#: Pool seed, redraw seed, premise tolerance (relative), central interval and budget (declared).
POOL_SEED, DRAW_SEED, PREMISE, CENTRAL, K = 3611, 3612, 0.05, (2.5, 97.5), 5
#: Pool size in a quick run.
QUICK_POOL = 2


def pool_truths(low: np.ndarray, high: np.ndarray, count: int, seed: int = POOL_SEED) -> np.ndarray:
    """``[count, d]`` truths uniform over the prior box (rounded to 6 digits, as a config stores them)."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    return np.round(low + (high - low) * np.random.default_rng(seed).random((count, low.size)), 6)


def per_truth(rows: pd.DataFrame) -> pd.Series:
    """Each truth's mean miss over its targets and seeds (the Table II cell's weights), by ``truth``."""
    return rows.groupby("truth", sort=True)["realized"].mean()


def redraw_cells(means: np.ndarray, n_truths: int, draws: int, seed: int = DRAW_SEED) -> np.ndarray:
    """``[draws]`` cells: truth sets of ``n_truths`` drawn with replacement from the pool's per-truth means."""
    means = np.asarray(means, float)
    pick = np.random.default_rng(seed).integers(0, means.size, size=(draws, n_truths))
    return means[pick].mean(axis=1)


def family_keys(rows: pd.DataFrame, family: str, draws: int) -> dict[str, float]:
    """One family's keys from its stored rows (``part``: ``stored`` = the frozen run's Probe-Robust(5) episodes,
    ``scene`` = the pool's scene on our truths, ``pool`` = the pool)."""
    from probecommit.studies.paper_values import value

    stored, scene, pool = (rows[rows["part"] == p] for p in ("stored", "scene", "pool"))
    n_truths = int(stored["truth"].nunique())
    s, c = float(stored["realized"].mean()), float(scene["realized"].mean())
    premise = abs(c - s) <= PREMISE * s
    means = per_truth(pool).to_numpy(float)
    cells = redraw_cells(means, n_truths, draws)
    lo, hi = np.percentile(cells, CENTRAL)
    paper = value(f"tab:breadth.{family}.probe_robust")
    toward = cells <= paper if paper < s else cells >= paper
    return {"n_truths": float(n_truths), "pool_truths": float(means.size), "draws": float(draws),
            "episodes_per_truth": float(len(pool) / max(means.size, 1)), "stored": s, "scene_frozen": c,
            "premise_rel_diff": abs(c - s) / s, "premise_holds": float(premise),
            "pool.min": float(means.min()), "pool.max": float(means.max()), "pool.mean": float(means.mean()),
            "draws.mean": float(cells.mean()), "draws.p025": float(lo), "draws.p975": float(hi),
            "paper": paper, "paper_inside": float(lo <= paper <= hi), "share_toward_paper": float(toward.mean())}


def keys(rows: pd.DataFrame, draws: int) -> dict[str, Any]:
    """Keys of ``explain:results.ex11_probe`` from the stored rows (one function for the step and verify)."""
    return {f"{family}.{k}": v for family, part in rows.groupby("family", sort=False)
            for k, v in family_keys(part, str(family), draws).items()}


def _truth_rows(run: Path, part: str, family: str) -> pd.DataFrame:
    """A run's Probe-Robust(k = 5) episodes (status ok) with each instance's truth label."""
    episodes = pd.read_parquet(run / "episodes.parquet")
    episodes = episodes[(episodes["method"] == "probe_robust") & (episodes["k"] == K) & (episodes["status"] == "ok")]
    instances = pd.read_parquet(run / "instances.parquet")
    latents = [c for c in instances.columns if c.startswith("true_")]
    label = instances[latents].round(6).astype(str).agg("|".join, axis=1)
    truth = dict(zip(instances["instance_id"], label))
    return pd.DataFrame({"family": family, "part": part, "truth": episodes["instance_id"].map(truth).to_numpy(),
                         "instance_id": episodes["instance_id"].to_numpy(), "repeat": episodes["repeat"].to_numpy(),
                         "realized": episodes["realized"].to_numpy(float)})


def _config(family: str, name: str, truths: list[list[float]] | None, engine: str | None, quick: bool) -> Any:
    """The frozen config (its quick version in a quick run) with Probe-Robust(5) only, ``truths`` and ``engine``."""
    from probecommit.runner.config import config_data, parse_config
    from probecommit.studies.breadth import paper_config, quick_config

    base = paper_config(family)
    data = config_data(quick_config(base) if quick else base)
    data["name"], data["methods"] = name, ["probe_robust"]
    data["probes"] = {**data["probes"], "budgets": [K]}
    if truths is not None:
        data["instances"] = {**data["instances"], "truths": truths}
    if engine is not None:
        data["simulator"] = {**data["simulator"], "engine": engine}
    return parse_config(data)


def _run_part(family: str, name: str, truths: list[list[float]] | None, engine: str | None, quick: bool, runs: Path,
              workers: int) -> Path:
    """One of the step's runs (:func:`_config`), in the process that calls it; its directory. Its units' large
    arrays get pages of their own (``large_arrays_apart``): in the heap, a push2d Probe-Robust unit's blocks left
    holes the next unit's did not fit, and the pool's run grew to 470-650 MB (216 MB apart, for about 10 s more CPU)."""
    from probecommit.process.memory import large_arrays_apart
    from probecommit.runner.study import run_study

    config = _config(family, name, truths, engine, quick)
    with large_arrays_apart():
        run_study(config, runs / config.name, workers=workers, threads=1)
    return runs / config.name


def family_rows(root: Path, runs: Path, family: str, quick: bool, workers: int) -> pd.DataFrame:
    """One family's stored rows: the frozen run's cell, the pool's scene on our truths, and the pool (run here).
    Each run is made in a process of its own (a config does not pickle, so it is built there from the family's
    name; issue 42, target 4): a push2d Probe-Robust run's working memory leaves with it."""
    from probecommit.runner.aside import in_own_process
    from probecommit.studies.explain.ex8_blind import _model, run_dir

    size, engine = FAMILIES[family]
    parts = [_truth_rows(run_dir(root, family, quick), "stored", family)]
    if engine is not None:
        scene = in_own_process(_run_part, family, f"ex11_{family}_scene", None, engine, quick, runs, workers)
        parts.append(_truth_rows(scene, "scene", family))
    else:  # the pool runs the frozen run's own engine: its scene on our truths is the stored run itself
        parts.append(parts[0].assign(part="scene"))
    model = _model(family)
    truths = pool_truths(model.prior_low, model.prior_high, QUICK_POOL if quick else size).tolist()
    pool = in_own_process(_run_part, family, f"ex11_{family}_pool", truths, engine, quick, runs, workers)
    parts.append(_truth_rows(pool, "pool", family))
    return pd.concat(parts, ignore_index=True)


def run(root: Path, runs: Path, draws: int, quick: bool = False,
        workers: int = 1) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows, for the families whose breadth runs are under ``root``."""
    from probecommit.studies.explain.ex8_blind import run_dir

    present = [f for f in FAMILIES if (run_dir(root, f, quick) / "episodes.parquet").is_file()]
    if not present:
        return {}, pd.DataFrame()
    rows = pd.concat([family_rows(root, runs, f, quick, workers) for f in present], ignore_index=True)
    return keys(rows, draws), rows


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``), with the published draw count."""
    if not (folder / STORED).is_file() or not published:
        return {}
    draws = int(next(v for k, v in published.items() if k.endswith(".draws")))
    return keys(pd.read_parquet(folder / STORED), draws)
