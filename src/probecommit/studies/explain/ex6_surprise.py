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
#: The label's budget: the final one, or the surprise's own.
WHEN = ("final", "own")


def labels(episodes: pd.DataFrame, index: pd.MultiIndex, k: int, final_k: int) -> dict[str, np.ndarray]:
    """``{"<when>_<label>": [E] bool}`` for trajectories in ``index`` order, read at ``final_k`` or ``k``."""
    out = {}
    for when, at in (("final", final_k), ("own", k)):
        rows = episodes[episodes["k"] == at].set_index(["instance_id", "repeat"]).reindex(index)
        for name, column, flag in LABELS:
            values = rows[column].astype(bool).to_numpy()
            out[f"{when}_{name}"] = values if flag else ~values
    return out


def reading_aucs(index: pd.MultiIndex, tables: dict[str, np.ndarray], episodes: pd.DataFrame, budgets: Sequence[int],
                 final_k: int, resamples: int, seed: int) -> dict[str, Any]:
    """Rank AUC (cluster-bootstrap triple) and the labelled count of every reading at each budget."""
    clusters = index.get_level_values(0).to_numpy()
    out: dict[str, Any] = {}
    for k in budgets:
        for label, y in labels(episodes, index, k, final_k).items():
            out[f"n.{label}.k{k}"] = int(y.sum())
            for reading, table in tables.items():
                iv = cluster_bootstrap_auc(table[:, k - 1], y, clusters, resamples=resamples, seed=seed)
                out[f"{reading}.{label}.k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    return out


def first_tap_pocket(run: Any, episodes: pd.DataFrame, final_k: int) -> dict[str, float]:
    """Share of final-budget escapes, and of the rest, whose first tap read the pocket floor."""
    from probecommit.studies.explain.surprise_variants import POCKET_CUT_MM

    probes = run.probes
    first = probes[probes["j"] == 1].set_index(["instance_id", "repeat"])["y"] < POCKET_CUT_MM
    last = episodes[episodes["k"] == final_k].set_index(["instance_id", "repeat"])["escaped"].astype(bool)
    pocket = first.reindex(last.index).to_numpy(bool)
    esc = last.to_numpy(bool)
    return {"first_tap_pocket.escaped": float(pocket[esc].mean()) if esc.any() else float("nan"),
            "first_tap_pocket.rest": float(pocket[~esc].mean()) if (~esc).any() else float("nan")}


def run(paper_test: Any, final_k: int, boot: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.ex6_surprise`` for the paper's-schedule Split B test run."""
    episodes = paper_test.episodes
    episodes = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    index, tables = run_tables(paper_test)
    out = reading_aucs(index, tables, episodes, [1, final_k], final_k, **boot)
    out.update(first_tap_pocket(paper_test, episodes, final_k))
    return out
