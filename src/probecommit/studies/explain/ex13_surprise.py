"""The surprise AUC over other draws of the generator under the paper's schedule (E106, T36 at k = 1).

Why: the paper (Sec. VI) reports that prequential surprise "detects final-budget escape on the
cover schedule (50 escaped, 334 covered test episodes) with rank AUC 0.85 at k = 1"; ours, on the
same schedule and Split B test set, is about 0.46 with 28 escapes. At k = 1 every trajectory has
tapped only -12 mm against the prior, so the AUC says how unevenly the first reading falls on
escapes and on the rest (for a binary score AUC = 0.5 + (TPR - FPR) / 2): it counts escapes from
the first tap's misread band, a property of which holes a 96-instance draw puts there. E15..E88
changed the reading, the label and the filter on one draw; this step reads five draws the explain
target already runs (no new engine run): Split B test, Split B calibration, Split A and the two
halves of the 192-instance re-split pool, all on MuJoCo under the paper's schedule and the
deployed model (docs/decisions.md, "ex13", declared before the run).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_auc

#: The stored rows (one per trajectory of every draw) the keys are summarized from.
STORED = "ex13_surprise_rows.parquet"
#: The draws, in the order they are reported.
DRAWS = ("b_test", "b_cal", "a", "pool_0", "pool_1")


def draw_rows(draw: str, episodes: pd.DataFrame, probes: pd.DataFrame, first_k: int, final_k: int,
              pocket_cut_mm: float) -> pd.DataFrame:
    """One row per trajectory of one draw: the stored running-max density surprise at ``first_k`` and
    ``final_k``, the paper's label (truth outside the full hull at ``final_k``) and whether the first tap read
    the pocket floor (reading below ``pocket_cut_mm``)."""
    e = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    key = ["instance_id", "repeat"]
    at = lambda k: e[e["k"] == k].set_index(key)  # noqa: E731
    first, last = at(first_k), at(final_k)
    index = last.index.sort_values()
    tap = probes[probes["j"] == 1].set_index(key)["y"].reindex(index)
    return pd.DataFrame({
        "draw": draw, "instance_id": index.get_level_values(0).astype(str),
        "repeat": index.get_level_values(1).astype("int64"),
        f"surprise_k{first_k}": first["max_surprise"].reindex(index).to_numpy(float),
        f"surprise_k{final_k}": last["max_surprise"].reindex(index).to_numpy(float),
        "escaped_final": last["escaped"].reindex(index).eq(True).to_numpy(bool),
        "first_tap_pocket": (tap < pocket_cut_mm).to_numpy(bool)})


def pool_halves(episodes: pd.DataFrame, probes: pd.DataFrame, instances: pd.DataFrame) -> list[tuple[pd.DataFrame, pd.DataFrame]]:
    """The re-split pool's episodes and probes split into its first and second half of instances (index order)."""
    order = instances.sort_values("instance_index")["instance_id"].astype(str).to_numpy()
    half = len(order) // 2
    out = []
    for ids in (set(order[:half]), set(order[half:])):
        out.append((episodes[episodes["instance_id"].astype(str).isin(ids)],
                    probes[probes["instance_id"].astype(str).isin(ids)]))
    return out


def summary(rows: pd.DataFrame, budgets: tuple[int, int], resamples: int, seed: int) -> dict[str, Any]:
    """Per draw: trajectories, final-budget escapes, the surprise AUC at both budgets (cluster-bootstrap
    triple), the first tap's pocket share among escapes and the rest; over the draws: the span of the point
    AUCs and of the escape counts (what ``supports`` reads; what verify recomputes)."""
    out: dict[str, Any] = {}
    points: dict[int, list[float]] = {k: [] for k in budgets}
    counts: list[int] = []
    names = [d for d in DRAWS if d in set(rows["draw"])]
    for draw in names:
        part = rows[rows["draw"] == draw]
        y, pocket = part["escaped_final"].to_numpy(bool), part["first_tap_pocket"].to_numpy(bool)
        out[f"{draw}.n"], out[f"{draw}.n_escaped"] = int(len(part)), int(y.sum())
        counts.append(int(y.sum()))
        for k in budgets:
            iv = cluster_bootstrap_auc(part[f"surprise_k{k}"].to_numpy(float), y, part["instance_id"].to_numpy(),
                                       resamples=resamples, seed=seed)
            out[f"{draw}.auc_k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
            points[k].append(float(iv.estimate))
        out[f"{draw}.first_tap_pocket.escaped"] = float(pocket[y].mean()) if y.any() else float("nan")
        out[f"{draw}.first_tap_pocket.rest"] = float(pocket[~y].mean()) if (~y).any() else float("nan")
    out["draws"] = len(names)
    for k, values in points.items():
        finite = [v for v in values if np.isfinite(v)]
        out[f"auc_k{k}.min"] = min(finite) if finite else float("nan")
        out[f"auc_k{k}.max"] = max(finite) if finite else float("nan")
    out["n_escaped.min"], out["n_escaped.max"] = (min(counts), max(counts)) if counts else (0, 0)
    return out


def run(paper_schedule: Mapping[str, Any], pool: Any, budgets: tuple[int, int], boot: dict[str, Any]
        ) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys of ``explain:results.ex13_surprise`` and the stored rows, from the paper's-schedule runs
    (``paper_schedule``: ``test``, ``cal``, ``A``) and the re-split pool's run under the same schedule."""
    from probecommit.studies.explain.surprise_variants import POCKET_CUT_MM

    first_k, final_k = budgets
    parts = []
    sources = [("b_test", paper_schedule["test"].episodes, paper_schedule["test"].probes),
               ("b_cal", paper_schedule["cal"].episodes, paper_schedule["cal"].probes),
               ("a", paper_schedule["A"].episodes, paper_schedule["A"].probes)]
    if pool is not None:
        halves = pool_halves(pool.episodes, pool.probes, pool.instances)
        sources += [(f"pool_{i}", e, p) for i, (e, p) in enumerate(halves)]
    for draw, episodes, probes in sources:
        parts.append(draw_rows(draw, episodes, probes, first_k, final_k, POCKET_CUT_MM))
    rows = pd.concat(parts, ignore_index=True)
    return summary(rows, budgets, **boot), rows
