"""The prequential-surprise AUC under every reading of the paper's words (E64).

Why: the paper (Sec. VI) reports that surprise "detects final-budget escape on the cover
schedule (50 escaped, 334 covered test episodes) with rank AUC 0.85 at k = 1 but 0.54 at
k = 5"; on the paper's schedule ours gives about 0.46 at k = 1. Word by word the definition
leaves three choices open, and each reading is one cell here:

* *probability*: the reading's density (what the runner stores) or its class's probability
  (``surprise_variants.class_surprise``);
* the *label*: the truth outside the full particle hull ("escape") or outside the retained set
  ("not covered", the paper's "334 covered");
* the label's *budget*: the final one (k = 5, the paper's words) or the surprise's own budget k.

At k = 1 on the paper's schedule every trajectory's first tap is at -12 mm and its belief is the
prior, so surprise there is a function of the first reading alone: the AUC says how many of the
labelled trajectories read the pocket on that tap.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_auc
from probecommit.studies.explain.surprise_variants import run_tables

#: The labels: (name, column of the episode table, True where the column flags the event).
LABELS = (("hull", "escaped", True), ("retained", "covered", False))
#: The stored rows (one per trajectory and budget read) the summaries come from.
STORED = "ex6_surprise_rows.parquet"


def table(index: pd.MultiIndex, tables: dict[str, np.ndarray], episodes: pd.DataFrame, probes: pd.DataFrame,
          budgets: Sequence[int], final_k: int) -> pd.DataFrame:
    """One row per trajectory and budget: each surprise reading, the labels at that budget and at the final one,
    and whether the trajectory's first tap read the pocket floor."""
    from probecommit.studies.explain.surprise_variants import POCKET_CUT_MM

    first = probes[probes["j"] == 1].set_index(["instance_id", "repeat"])["y"].reindex(index) < POCKET_CUT_MM
    at = lambda k, column: episodes[episodes["k"] == k].set_index(["instance_id", "repeat"])[column].reindex(index)  # noqa: E731
    parts = []
    for k in budgets:
        parts.append(pd.DataFrame({
            "instance_id": index.get_level_values(0).astype(str), "repeat": index.get_level_values(1).astype(int),
            "k": int(k), **{reading: t[:, k - 1] for reading, t in tables.items()},
            "escaped_own": at(k, "escaped").eq(True).to_numpy(), "covered_own": at(k, "covered").eq(True).to_numpy(),
            "escaped_final": at(final_k, "escaped").eq(True).to_numpy(),
            "covered_final": at(final_k, "covered").eq(True).to_numpy(), "first_tap_pocket": first.to_numpy(bool)}))
    return pd.concat(parts, ignore_index=True)


def summary(rows: pd.DataFrame, resamples: int, seed: int) -> dict[str, Any]:
    """Rank AUC (cluster-bootstrap triple) and labelled count of every reading at each budget, and the first
    tap's pocket share among final-budget escapes and the rest, from the stored rows (what verify recomputes)."""
    out: dict[str, Any] = {}
    readings = [c for c in ("density", "class") if c in rows.columns]
    for k, part in rows.groupby("k"):
        clusters = part["instance_id"].to_numpy()
        for when in ("final", "own"):
            for name, column, flag in LABELS:
                y = part[f"{column}_{when}"].to_numpy(bool)
                y = y if flag else ~y
                out[f"n.{when}_{name}.k{int(k)}"] = int(y.sum())
                for reading in readings:
                    iv = cluster_bootstrap_auc(part[reading].to_numpy(float), y, clusters, resamples=resamples, seed=seed)
                    out[f"{reading}.{when}_{name}.k{int(k)}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    first = rows[rows["k"] == rows["k"].min()]
    esc, pocket = first["escaped_final"].to_numpy(bool), first["first_tap_pocket"].to_numpy(bool)
    out["first_tap_pocket.escaped"] = float(pocket[esc].mean()) if esc.any() else float("nan")
    out["first_tap_pocket.rest"] = float(pocket[~esc].mean()) if (~esc).any() else float("nan")
    return out


def run(paper_test: Any, final_k: int, boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys of ``explain:results.ex6_surprise`` for the paper's-schedule Split B test run, and the stored rows."""
    episodes = paper_test.episodes
    episodes = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    index, tables = run_tables(paper_test)
    rows = table(index, tables, episodes, paper_test.probes, [1, final_k], final_k)
    return summary(rows, **boot), rows
