"""The mixture's cost when the model is right, against the particle filter's own noise (E46).

Why: the paper's contamination mixture ``(1 - eps) p + eps q0``, ``q0`` uniform over the 19 mm
observable height range, is ours term for term, yet with the right model ours at eps = 0.01
changes a few aims and costs nothing while the paper's costs 0.102 -> 0.167. Our replay holds
the filter's random numbers fixed between the two arms; the paper does not say whether its two
runs shared them. This step re-infers the harness run (right model, stored probes) under other
filter seeds, with and without the mixture: the paired cost per seed, and the differences
between independently seeded runs, say how much of a 0.065 gap the filter's noise alone makes.
"""

from __future__ import annotations

from itertools import product
from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.replay import LoadedRun
from probecommit.studies.explain.replay_final import replay_at


def _final(episodes: pd.DataFrame, k: int) -> pd.DataFrame:
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok") & (episodes["k"] == k)]
    return rows.sort_values(["instance_id", "repeat"]).reset_index(drop=True)


def reseeded(run: LoadedRun, seed: int) -> LoadedRun:
    """``run`` with another study seed: a replay then draws other filter random numbers (the probes are stored)."""
    return LoadedRun(run.path, run.config.model_copy(update={"seed": int(seed)}), run.instances, manifest=run.manifest)


def unpaired_differences(treated: list[float], control: list[float]) -> np.ndarray:
    """``treated[s] - control[t]`` over every ordered pair of distinct seeds ``s != t``."""
    return np.array([a - b for (i, a), (j, b) in product(enumerate(treated), enumerate(control)) if i != j])


def _summary(prefix: str, values: np.ndarray) -> dict[str, float]:
    return {f"{prefix}.mean": float(values.mean()), f"{prefix}.sd": float(values.std(ddof=1)),
            f"{prefix}.min": float(values.min()), f"{prefix}.max": float(values.max()),
            f"{prefix}.p025": float(np.quantile(values, 0.025)), f"{prefix}.p975": float(np.quantile(values, 0.975))}


#: The stored per-seed rows (``explain/results/``): what the summary is computed from.
STORED = "mixture_noise_seeds.parquet"


def run(base: LoadedRun, mixture: dict[str, Any], seeds: list[int], k: int) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys of ``explain:results.mixture_noise`` (``summary``) and the per-seed rows they summarize: the right
    model and the mixture under each filter seed."""
    rows = []
    frozen = _final(base.episodes, k)
    for seed in seeds:
        loaded = reseeded(base, seed)
        r = _final(replay_at(loaded, None, k), k)  # only the final budget is read: only it is committed
        m = _final(replay_at(loaded, {"belief": mixture}, k), k)
        rows.append({"seed": int(seed), "epsilon": float(mixture["epsilon"]), "right": float(r["realized"].mean()),
                     "mixed": float(m["realized"].mean()),
                     "changed": float((r["action"].to_numpy() != m["action"].to_numpy()).mean()),
                     "changed_seed": float((r["action"].to_numpy() != frozen["action"].to_numpy()).mean())})
    table = pd.DataFrame(rows, columns=["seed", "epsilon", "right", "mixed", "changed", "changed_seed"])
    return summary(table), table


def summary(table: pd.DataFrame) -> dict[str, Any]:
    """The per-seed rows summarized (the explain step and ``verify`` both call this): each arm's failure, the
    paired and the unpaired cost over seeds, and the shares of changed aims."""
    right, mixed = table["right"].to_numpy(float), table["mixed"].to_numpy(float)
    out: dict[str, Any] = {"seeds": len(table), "epsilon": float(table["epsilon"].iloc[0])}
    out.update(_summary("right.failure", right))
    out.update(_summary("mixture.failure", mixed))
    out.update(_summary("paired_cost", mixed - right))
    out.update(_summary("unpaired_cost", unpaired_differences(list(mixed), list(right))))
    out["paired_changed_aims.mean"] = float(np.mean(table["changed"].to_numpy(float)))
    out["reseeded_changed_aims.mean"] = float(np.mean(table["changed_seed"].to_numpy(float)))
    return out
