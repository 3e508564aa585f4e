"""The fault harness read as the paper reads it (E69, E70; ``docs/decisions.md``, ex7).

Why: two of the paper's fault-class statements differ from ours as the registry reads them.
"Particle impoverishment raises support escape while the score residual *improves*" sits beside
"the boundary error climbs ... and optimism climbs with it": a reading over the budget (E69), which
this module measures per episode from k = 1 to the final budget. Table VIII's surprise AUCs are
read from the predictive *density* the runner stores; the paper says predictive *probability*,
E16's class reading (:func:`~probecommit.studies.explain.surprise_variants.class_surprise`), which
E70 applies to every harness row with a printed surprise. Both run on the MuJoCo harness's stored
probes; nothing is rerun on the engine.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_auc, cluster_bootstrap_mean
from probecommit.runner.replay import LoadedRun, replay_config
from probecommit.studies.explain import surprise_variants
from probecommit.studies.faults import Arm

#: Table VIII's rows with a printed surprise AUC (E70 tests one definition against all of them).
SURPRISE_ROWS = ("boundary", "prior", "particles")


def _arm_rows(episodes: pd.DataFrame, fault: str, k: int) -> pd.DataFrame:
    """The fault arm's ok probe-executor rows at budget ``k``, one per (instance, repeat), in order."""
    rows = episodes[(episodes["fault"] == fault) & (episodes["arm"] == "fault") & (episodes["method"] == "probe_robust")
                    & (episodes["status"] == "ok") & (episodes["k"] == k)]
    rows = rows.assign(optimism=rows["realized"] - rows["predicted"])
    return rows.set_index(["instance_id", "repeat"]).sort_index()


def _paired_mean(first: pd.DataFrame, second: pd.DataFrame, column: str, boot: dict[str, int]) -> list[float]:
    """Mean of ``second - first`` on ``column`` over the episodes both hold, cluster-bootstrapped over instances."""
    both = first[[column]].merge(second[[column]], left_index=True, right_index=True, suffixes=("_a", "_b"))
    diff = both[f"{column}_b"].to_numpy(float) - both[f"{column}_a"].to_numpy(float)
    iv = cluster_bootstrap_mean(diff, both.index.get_level_values(0).to_numpy(), **boot)
    return [float(iv.estimate), float(iv.lo), float(iv.hi)]


def budget_change(episodes: pd.DataFrame, fault: str, first: int, last: int, column: str,
                  boot: dict[str, int]) -> list[float]:
    """Mean per-episode change of ``column`` (``escaped`` or ``optimism``) from budget ``first`` to ``last`` on
    ``fault``'s arm, with a cluster-bootstrap interval over instances: ``[estimate, lo, hi]``."""
    return _paired_mean(_arm_rows(episodes, fault, first), _arm_rows(episodes, fault, last), column, boot)


def paired_against(episodes: pd.DataFrame, fault: str, other: str, k: int, column: str,
                   boot: dict[str, int]) -> list[float]:
    """``fault`` minus ``other`` on ``column`` at budget ``k``, paired by episode (identical stored probes)."""
    return _paired_mean(_arm_rows(episodes, other, k), _arm_rows(episodes, fault, k), column, boot)


def signature_keys(episodes: pd.DataFrame, kmax: int, boot: dict[str, int]) -> dict[str, Any]:
    """E69's keys: over the budget (k = 1 to ``kmax``) the particle fault's escape and optimism change, the
    boundary fault's optimism change, and the particle fault against the baseline at ``kmax``."""
    return {
        "particles.escape_change": budget_change(episodes, "particles", 1, kmax, "escaped", boot),
        "particles.optimism_change": budget_change(episodes, "particles", 1, kmax, "optimism", boot),
        "boundary.escape_change": budget_change(episodes, "boundary", 1, kmax, "escaped", boot),
        "boundary.optimism_change": budget_change(episodes, "boundary", 1, kmax, "optimism", boot),
        "particles_minus_none.optimism_final": paired_against(episodes, "particles", "none", kmax, "optimism", boot),
    }


def arm_surprise_aucs(run: LoadedRun, arm: Arm, episodes: pd.DataFrame, kmax: int,
                      boot: dict[str, int]) -> tuple[dict[str, Any], pd.DataFrame]:
    """AUC at ``kmax`` of the density and the class surprise for final-budget escape on one fault arm, its beliefs
    recomputed from ``run``'s stored probes under the arm's overrides; and the per-episode rows they come from. A class
    no particle predicted is stored as its surprise, ``+inf`` (declared in ``report.checks``), which the AUC ranks above
    every finite one: a finite stand-in would be a number the definition never gives."""
    index, tables = surprise_variants.run_tables(run, config=replay_config(run.config, arm.overrides))
    label = _arm_rows(episodes, arm.fault, kmax)["escaped"].reindex(index)
    rows = pd.DataFrame({"fault": arm.fault, "instance_id": index.get_level_values(0),
                         "repeat": index.get_level_values(1), "escaped": label.to_numpy(object),
                         "density": tables["density"][:, kmax - 1], "class": tables["class"][:, kmax - 1]})
    rows = rows[label.notna().to_numpy()].astype({"escaped": bool}).reset_index(drop=True)  # no ok row: no label
    return surprise_keys(rows, boot), rows


#: The largest finite surprise a float64 probability can give, -log of the smallest positive float64 (about 744.4): a
#: stored surprise above it is one whose probability was 0, whether stored as +inf or (publications before the
#: rows kept +inf) as 745.
LARGEST_FINITE_SURPRISE = float(-np.log(np.nextafter(0.0, 1.0)))


def surprise_keys(rows: pd.DataFrame, boot: dict[str, int]) -> dict[str, Any]:
    """Per surprise reading, the AUC (cluster-bootstrap triple) of the stored per-episode rows of one arm."""
    y, clusters = rows["escaped"].to_numpy(bool), rows["instance_id"].to_numpy()
    out: dict[str, Any] = {"n_escaped": int(y.sum()), "n_class_unpredicted": int((rows["class"] > LARGEST_FINITE_SURPRISE).sum())}
    for reading in ("density", "class"):
        iv = cluster_bootstrap_auc(rows[reading].to_numpy(float), y, clusters, **boot)
        out[f"{reading}_auc"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    return out


def equals_table(keys: dict[str, Any], table_faults: dict[str, Any], fault: str) -> int:
    """1 when ``keys``' density AUC is Table VIII's surprise AUC for ``fault`` (same data, two paths), else 0."""
    stored = table_faults.get(fault, {}).get("surprise_auc")
    return int(stored is not None and abs(keys["density_auc"][0] - stored) < 1e-9)


#: The per-episode surprise rows E70's AUCs come from (``explain/results/``).
STORED = "ex7_fault_surprise.parquet"


def run(job: Any) -> None:
    """Fill ``explain:results.ex7_faults`` (E69, E70) from the harness's stored episodes and probes."""
    from probecommit.studies.faults import fault_arms

    p, f = job.p, job.p.faults
    kmax = p.budgets["random"]
    episodes = job.fault_episodes()
    out = job.res["ex7_faults"]
    out.update({f"signature.{k}": v for k, v in signature_keys(episodes, kmax, job.boot).items()})
    arms = {a.fault: a for a in fault_arms(f.noise_factor, f.prior_half_width, f.particles, f.frame_offset,
                                           f.temperature, p.sigma) if a.arm == "fault"}
    source = {"base": "faults_base", "prior": "faults_prior", "noise": "faults_noise"}
    stored_auc = job.insertion_results()["table_faults"]
    parts = []
    for fault in SURPRISE_ROWS:
        arm = arms[fault]
        keys, rows = arm_surprise_aucs(job.load(source[arm.rollout]), arm, episodes, kmax, job.boot)
        out.update({f"surprise.{fault}.{k}": v for k, v in keys.items()})
        out[f"surprise.{fault}.density_equals_table"] = equals_table(keys, stored_auc, fault)
        parts.append(rows)
    job.stored[STORED] = pd.concat(parts, ignore_index=True)
