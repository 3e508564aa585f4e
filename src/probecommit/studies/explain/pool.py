"""The committed pool of a commit gate, under each reading of the paper's definitions.

The paper (Sec. VI): on the cover schedule, budgets 1..5, a trajectory commits at the first
budget whose signal is at most tau (first passage); tau is the threshold committing about
60 %; an episode is *escaped* when the truth lies outside the full particle hull at the
schedule's final budget k = 5; claimed score and realized failure are read at each committed
trajectory's own stopping budget. ``audit.gates`` implements exactly that. Here the same
pool is re-read with the escape label defined other ways, so a reader can see which
definition, if any, moves the committed-to-rejected ratio.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.gates import first_passage, gates_from_tables, trajectory_matrix
from probecommit.audit.stats import cluster_bootstrap_auc
from probecommit.studies.explain.stats import pool_escape_ratio

#: Escape labels compared (the first is the paper's).
VARIANTS = ("final_hull", "stop_hull", "ever_hull", "final_retained")


def pool_variants(raw: pd.DataFrame, budgets: Sequence[int], *, resamples: int, seed: int) -> dict[str, Any]:
    """The raw gate's pool at its 60 % operating point under each escape label.

    Args:
        raw: Probe-Robust episodes of the ``nu`` executor (one method and variant).
        budgets: The nested budgets of the gate.

    Returns:
        Per variant ``escaped_committed``, ``escaped_rejected``, and for the paper's label
        the rates and their ratio with cluster-bootstrap intervals; plus the operating
        point and how confident the escaped trajectories look to the gate.
    """
    index, budgets, pred = trajectory_matrix(raw, "predicted", budgets)
    escaped = trajectory_matrix(raw, "escaped", budgets, index)[2].astype(bool)
    covered = trajectory_matrix(raw, "covered", budgets, index)[2].astype(bool)
    summary = gates_from_tables(raw, None, budgets=budgets).summary.set_index("signal")
    tau = float(summary.loc["raw", "tau"])
    stop = first_passage(pred, tau)
    committed = stop >= 0
    rows = np.arange(len(stop))
    at_stop = np.where(committed, escaped[rows, np.maximum(stop, 0)], escaped[:, -1])
    labels = {"final_hull": escaped[:, -1], "stop_hull": at_stop, "ever_hull": escaped.any(axis=1),
              "final_retained": ~covered[:, -1]}
    clusters = index.get_level_values("instance_id").to_numpy()
    out: dict[str, Any] = {"tau": tau, "n_committed": int(committed.sum()), "n_rejected": int((~committed).sum()),
                           "commit_rate": float(committed.mean()), "claimed": float(summary.loc["raw", "claimed"]),
                           "realized": float(summary.loc["raw", "realized"])}
    if "posterior_variance" in summary.index:
        pv = summary.loc["posterior_variance"]
        out["posterior_variance.escaped_committed"] = int(pv["escaped_committed"])
        out["posterior_variance.n_committed"] = int(pv["n_committed"])
        out["posterior_variance.escaped_rejected"] = int(pv["escaped_rejected"])
    for name, label in labels.items():
        out[f"{name}.escaped_committed"] = int(label[committed].sum())
        out[f"{name}.escaped_rejected"] = int(label[~committed].sum())
    for name in ("final_hull", "stop_hull"):
        ratio = pool_escape_ratio(committed, labels[name], clusters, resamples=resamples, seed=seed)
        out.update({f"{name}.{k}": v for k, v in ratio.items()})
    if "posterior_variance" in summary.index and "post_var" in raw.columns:
        # The posterior-variance gate's own pool (its first passage at its own 60 % tau), paper's label.
        variance = trajectory_matrix(raw, "post_var", budgets, index)[2]
        held = first_passage(variance, float(summary.loc["posterior_variance", "tau"])) >= 0
        ratio = pool_escape_ratio(held, labels["final_hull"], clusters, resamples=resamples, seed=seed)
        out.update({f"posterior_variance.final_hull.{k}": v for k, v in ratio.items()})
    # Do escaped trajectories look confident? The rank AUC of (minus) the smallest raw score
    # over the budgets for final escape: above 0.5, escapes reach lower scores than the rest.
    best = np.nanmin(pred, axis=1)
    auc = cluster_bootstrap_auc(-best, labels["final_hull"], clusters, resamples=resamples, seed=seed)
    out["confidence_auc"] = [auc.estimate, auc.lo, auc.hi]
    out["fraction_of_escapes_committed"] = float(labels["final_hull"][committed].sum() / max(labels["final_hull"].sum(), 1))
    return out


def gate_pools(result: Any) -> dict[str, Any]:
    """Areas and pools of a ``GatesResult`` as flat keys (``<signal>.area``, ...)."""
    out: dict[str, Any] = {}
    for row in result.summary.to_dict("records"):
        name = row["signal"]
        for key in ("area", "mean_failure", "c_min", "c_max", "tau", "commit_rate", "n_committed", "escaped_committed", "n_rejected",
                    "escaped_rejected", "claimed", "realized"):
            if key in row and row[key] == row[key]:  # skip NaN
                value = row[key]
                out[f"{name}.{key}"] = int(value) if isinstance(value, (np.integer,)) else float(value) \
                    if not isinstance(value, (int,)) else value
    return out
