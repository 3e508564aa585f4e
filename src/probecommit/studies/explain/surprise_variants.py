"""Prequential surprise read two ways, to test what the paper's k = 1 AUC measures.

The paper (Sec. VI) defines surprise as "the negative log predictive *probability* of each
tap before it is assimilated, aggregated by the maximum over the taps seen". The runner
stores the negative log predictive *density* of the continuous reading, which adds the tap
noise's own ``(y - level)^2 / 2 sigma^2`` to every tap; a tap reads one of two levels 30
sigma apart, so the probability of the reading's class is the other reading of the words.
This module recomputes that class probability from the stored beliefs: if the definition
were the cause of the k = 1 gap, the AUC under it would move to the paper's value.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_auc

#: A reading below this (mm) is the pocket floor (-15 mm), above it the plate top (0 mm).
POCKET_CUT_MM = -7.5


def class_surprise(weights: np.ndarray, predicts_pocket: np.ndarray, reads_pocket: np.ndarray) -> np.ndarray:
    """``-log P(observed class)`` per episode: the weight of the particles that predict the class read.

    Args:
        weights: ``[E, N]`` normalized particle weights before the tap.
        predicts_pocket: ``[E, N]`` whether each particle predicts the pocket reading.
        reads_pocket: ``[E]`` whether the tap read the pocket.

    Returns:
        ``[E]``; ``inf`` where no particle predicts the class read.
    """
    w = np.asarray(weights, dtype=float)
    pocket = np.sum(w * np.asarray(predicts_pocket, dtype=bool), axis=1)
    p = np.where(np.asarray(reads_pocket, dtype=bool), pocket, 1.0 - pocket)
    with np.errstate(divide="ignore"):
        return -np.log(np.clip(p, 0.0, None))


def surprise_tables(trace: Any, model: Any) -> dict[str, np.ndarray]:
    """Per tap ``[E, K]``: the stored density surprise and the class surprise, each as its running maximum."""
    batch, density = trace.batch, np.asarray(trace.surprise, dtype=float)
    cls = np.full(density.shape, np.nan)
    for j in range(1, density.shape[1] + 1):
        state = trace.states[j - 1]
        predicts = model.reads_pocket(batch.u[:, j - 1], state.particles)
        cls[:, j - 1] = class_surprise(np.exp(state.log_weights), predicts, batch.y[:, j - 1, 0] < POCKET_CUT_MM)
    return {"density": np.fmax.accumulate(density, axis=1), "class": np.fmax.accumulate(cls, axis=1)}


def run_tables(run: Any, chunk_instances: int = 24, config: Any = None) -> tuple[pd.MultiIndex, dict[str, np.ndarray]]:
    """``surprise_tables`` of a whole run, its beliefs recomputed a chunk of instances at a time (bounded memory);
    ``config``: infer under it instead of the run's (a replay's, e.g. a fault arm's)."""
    from probecommit.runner.replay import RunBeliefs

    beliefs = RunBeliefs.of(run, config, chunk_instances=chunk_instances)
    ids, reps, parts = [], [], []
    for rows in beliefs.chunks:
        trace = beliefs.trace(rows)
        ids.append(trace.batch.instance_id.astype(str))
        reps.append(trace.batch.repeat.astype(int))
        parts.append(surprise_tables(trace, beliefs.model))
        del trace
    index = pd.MultiIndex.from_arrays([np.concatenate(ids), np.concatenate(reps)])
    return index, {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}


#: The stored surprise readings per trajectory and budget (``schedule``, ``instance_id``, ``repeat``,
#: ``<reading>_k<k>``): what :func:`aucs_from_table` ranks.
STORED = "surprise_variants.parquet"


def variant_table(run: Any, schedule: str) -> pd.DataFrame:
    """Each trajectory's running-max surprise under every reading at every budget (``run_tables``), one row each."""
    index, tables = run_tables(run)
    out = pd.DataFrame({"schedule": schedule, "instance_id": index.get_level_values(0).to_numpy(str),
                        "repeat": index.get_level_values(1).to_numpy("int64")})
    for reading, table in tables.items():
        for j in range(table.shape[1]):
            out[f"{reading}_k{j + 1}"] = table[:, j].astype(float)
    return out


def aucs_from_table(rows: pd.DataFrame, episodes: pd.DataFrame, budgets: list[int], final_k: int,
                    resamples: int, seed: int) -> dict[str, list[float]]:
    """Rank AUC (cluster-bootstrap triple) of each surprise reading at each budget, for two escape labels:
    the paper's (outside the full hull at ``final_k``) and "outside the retained set" at ``final_k``; ``rows``
    one schedule's ``variant_table``, ``episodes`` its Probe-Robust rows (``escaped``, ``covered`` per budget)."""
    index = pd.MultiIndex.from_arrays([rows["instance_id"].to_numpy(str), rows["repeat"].to_numpy("int64")])
    last = episodes[episodes["k"] == final_k]
    last = last.set_index([last["instance_id"].astype(str), last["repeat"].astype("int64")]).reindex(index)
    labels = {"final_hull": last["escaped"].to_numpy(bool), "final_retained": ~last["covered"].to_numpy(bool)}
    clusters = index.get_level_values(0).to_numpy()
    readings = dict.fromkeys(c.rsplit("_k", 1)[0] for c in rows.columns if "_k" in c)
    out: dict[str, list[float]] = {}
    for reading in readings:
        for label, y in labels.items():
            for k in budgets:
                iv = cluster_bootstrap_auc(rows[f"{reading}_k{k}"].to_numpy(float), y, clusters, resamples=resamples, seed=seed)
                out[f"{reading}.{label}.k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    return out
