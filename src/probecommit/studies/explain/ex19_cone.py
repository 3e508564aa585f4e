"""2-D push (MuJoCo) under the pyramidal friction cone over redrawn truth sets (E139).

Why: the paper's 2-D push row is the one where five probes barely help (Probe-Robust 0.221 against
Blind-Robust 0.307); ours removes most of the miss. E50 tested MuJoCo's default pyramidal cone (friction
that depends on the sliding direction, invisible to probes along +x) on our three truths only; E95
redrew the truths under our elliptic cone only. Cause under test: both at once. E95's pool of truths
(its stored Probe-Robust(5) actions) and the frozen run's stored blind actions are re-executed at every
pool truth in the frozen scene with the pyramidal cone; when the probes read the same under both cones
(premise), the beliefs and actions are the elliptic run's, so this is the pool's study under that cone.
Three-truth sets are redrawn from the pool, the three cells from one set (docs/decisions.md, "ex19").
Every key is computed by :func:`keys` from the stored rows (misses and probe readings), so ``verify``
recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

FAMILY = "push2d"
ARMS = ("blind_bayes", "blind_robust", "probe_robust")
CONES = ("pyramidal", "elliptic")
#: The stored rows, beside results.json.
STORED = "ex19_cone_rows.parquet"
#: Redraw seed, truths per set (the paper's pushing truths), central band, premises (m) and budget (declared).
SEED, N_TRUTHS, CENTRAL, PROBE_M, REPLAY_M, K = 3901, 3, (2.5, 97.5), 0.0005, 1e-6, 5
LATENTS = ("true_mu", "true_m", "true_k_d")


def _with_instances(run: Path) -> pd.DataFrame:
    ep = pd.read_parquet(run / "episodes.parquet")
    ins = pd.read_parquet(run / "instances.parquet")
    return ep[ep["status"] == "ok"].merge(ins[["instance_id", *LATENTS, "ctx_target_x", "ctx_target_y"]],
                                          on="instance_id", how="left")


def _label(theta: tuple[float, ...]) -> str:
    """A pool truth's label (its latents to six digits, as a config stores them)."""
    return "|".join(f"{float(v):.6f}" for v in theta)


def _miss(scene: Any, theta: tuple[float, ...], action: tuple[float, float], target: tuple[float, float]) -> float:
    rest = scene.rest_of(theta, action)
    return float(np.hypot(rest[0] - target[0], rest[1] - target[1]))


def miss_rows(pool: pd.DataFrame, blind: pd.DataFrame, scene: Any, cone: str) -> pd.DataFrame:
    """Every pool truth's misses in ``scene``: its own Probe-Robust(5) episodes (with the stored miss) and every
    stored blind action of the frozen run at the same target (E76's weighting)."""
    rows = []
    probe = pool[(pool["method"] == "probe_robust") & (pool["k"] == K)]
    for r in probe.itertuples(index=False):
        theta = (r.true_mu, r.true_m, r.true_k_d)
        rows.append((cone, _label(theta), "probe_robust", r.ctx_target_x,
                     r.ctx_target_y, r.action_0, r.action_1,
                     _miss(scene, theta, (r.action_0, r.action_1), (r.ctx_target_x, r.ctx_target_y)), r.realized))
    truths = probe[list(LATENTS)].drop_duplicates().itertuples(index=False)
    arms = blind[blind["method"].isin(ARMS[:2]) & (blind["k"] == 0)]
    for theta in truths:
        label = _label(tuple(theta))
        for r in arms.itertuples(index=False):
            rows.append((cone, label, r.method, r.ctx_target_x, r.ctx_target_y, r.action_0, r.action_1,
                         _miss(scene, tuple(theta), (r.action_0, r.action_1), (r.ctx_target_x, r.ctx_target_y)),
                         np.nan))
    return pd.DataFrame(rows, columns=["cone", "truth", "method", "target_x", "target_y", "action_0", "action_1",
                                       "realized", "stored"]).assign(kind="miss")


def probe_rows(truths: list[tuple[float, ...]], scenes: dict[str, Any], pulses: tuple[float, ...]) -> pd.DataFrame:
    """Noise-free probe rests (pulses along +x) at every pool truth under each cone (premise a)."""
    rows = []
    for theta in truths:
        label = _label(theta)
        for cone, scene in scenes.items():
            for u in pulses:
                rest = scene.rest_of(tuple(theta), (u, 0.0))
                rows.append((cone, label, float(u), float(rest[0]), float(rest[1])))
    return pd.DataFrame(rows, columns=["cone", "truth", "pulse", "x", "y"]).assign(kind="probe")


def bands(means: pd.DataFrame, draws: int) -> dict[str, np.ndarray]:
    """``[draws]`` cells per arm and the two ratios: three-truth sets drawn with replacement from the pool's
    per-truth means (``means``: truths x arms), the three cells from one set."""
    pick = np.random.default_rng(SEED).integers(0, len(means), size=(draws, N_TRUTHS))
    cells = {arm: means[arm].to_numpy(float)[pick].mean(axis=1) for arm in ARMS}
    cells["probe_over_robust"] = cells["probe_robust"] / cells["blind_robust"]
    cells["robust_over_bayes"] = cells["blind_robust"] / cells["blind_bayes"]
    return cells


def paper_cells() -> dict[str, float]:
    from probecommit.studies.paper_values import value

    p = {arm: value(f"tab:breadth.{FAMILY}.{arm}") for arm in ARMS}
    p["probe_over_robust"] = p["probe_robust"] / p["blind_robust"]
    p["robust_over_bayes"] = p["blind_robust"] / p["blind_bayes"]
    return p


def keys(rows: pd.DataFrame, draws: int) -> dict[str, Any]:
    """Keys of ``explain:results.ex19_cone`` from the stored rows (one function for the step and verify)."""
    miss, probe = rows[rows["kind"] == "miss"], rows[rows["kind"] == "probe"]
    readings = probe.pivot_table(index=["truth", "pulse"], columns="cone", values=["x", "y"])
    probe_m = float(max((readings["x"]["pyramidal"] - readings["x"]["elliptic"]).abs().max(),
                        (readings["y"]["pyramidal"] - readings["y"]["elliptic"]).abs().max()))
    replay = miss[(miss["cone"] == "elliptic") & (miss["method"] == "probe_robust")]
    replay_m = float((replay["realized"] - replay["stored"]).abs().max())
    out: dict[str, Any] = {"pool_truths": float(miss["truth"].nunique()), "draws": float(draws),
                           "n_truths": float(N_TRUTHS), "premise.probe_max_m": probe_m,
                           "premise.replay_max_m": replay_m}
    out["premise_holds"] = float(probe_m <= PROBE_M and replay_m <= REPLAY_M)
    paper = paper_cells()
    for cone in CONES:
        means = miss[miss["cone"] == cone].groupby(["truth", "method"])["realized"].mean().unstack("method")
        cells = bands(means[list(ARMS)], draws)
        for name, values in cells.items():
            lo, hi = np.percentile(values, CENTRAL)
            out.update({f"{cone}.{name}.mean": float(values.mean()), f"{cone}.{name}.p025": float(lo),
                        f"{cone}.{name}.p975": float(hi),
                        f"{cone}.{name}.paper_inside": float(lo <= paper[name] <= hi)})
        for arm in ARMS:
            out[f"{cone}.{arm}.pool_min"] = float(means[arm].min())
            out[f"{cone}.{arm}.pool_max"] = float(means[arm].max())
    out.update({f"paper.{k}": v for k, v in paper.items()})
    inside = all(out[f"pyramidal.{n}.paper_inside"] == 1 for n in (*ARMS, "probe_over_robust"))
    out["pyramidal.all_inside"] = float(inside)
    out["holds"] = float(out["premise_holds"] == 1 and inside and out["elliptic.probe_robust.paper_inside"] == 0)
    return out


def run(root: Path, runs: Path, draws: int, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """Re-execute E95's pool (``runs/ex11_push2d_pool``) and the frozen blind actions under both cones."""
    from probecommit.studies.explain.ex4_cone import PULSES, Scene
    from probecommit.studies.explain.ex8_blind import run_dir

    pool_dir, frozen = Path(runs) / "ex11_push2d_pool", run_dir(root, FAMILY, quick)
    if not ((pool_dir / "episodes.parquet").is_file() and (frozen / "episodes.parquet").is_file()):
        return {}, pd.DataFrame()
    pool, blind = _with_instances(pool_dir), _with_instances(frozen)
    scenes = {cone: Scene(cone) for cone in CONES}
    truths = [tuple(t) for t in pool[list(LATENTS)].drop_duplicates().itertuples(index=False)]
    rows = pd.concat([*(miss_rows(pool, blind, scenes[c], c) for c in CONES), probe_rows(truths, scenes, PULSES)],
                     ignore_index=True)
    return keys(rows, draws), rows


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``), with the published draw count."""
    if not (folder / STORED).is_file() or not published:
        return {}
    return keys(pd.read_parquet(folder / STORED), int(published["draws"]))
