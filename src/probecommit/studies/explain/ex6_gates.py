"""Which random-probe commit gate is lowest when the gates are compared over the same range (E63).

Why: the paper says that under random probing posterior variance has the lowest area under the
failure-vs-commit-rate curve; ours gives raw the lowest. Each area is "a point estimate over each
method's attainable range" (Fig. 6's caption), and the ranges are not equal: on our frozen
Split B random run the raw gate's curve starts at about 35 % commitment (a third of the
trajectories tie at its smallest score), the others near 0 %, so raw's integral covers about
two thirds of the axis. The cause tested is that the unnormalized area rewards a short range.
It is removed two ways: every deployable gate integrated over the common range (the largest
``c_min`` to the smallest ``c_max``), and each area divided by its own range (the mean failure
over it), the latter over cluster-bootstrap resamples of the test instances.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.gates import curve_area, gate_curve, trajectory_matrix

#: The deployable gates compared (the oracle is not).
DEPLOYABLE = ("raw", "adjusted", "posterior_variance")
#: The stored rows (the two executors' test episodes the gates read).
STORED = "ex6_random_gates.parquet"


def area_between(curve: pd.DataFrame, lo: float, hi: float) -> float:
    """Trapezoid area of ``failure`` over ``commit_rate`` restricted to ``[lo, hi]`` (points in threshold
    order; a segment is interpolated linearly where the range cuts it; vertical segments add nothing)."""
    c, f = curve["commit_rate"].to_numpy(float), curve["failure"].to_numpy(float)
    total = 0.0
    for c0, c1, f0, f1 in zip(c[:-1], c[1:], f[:-1], f[1:]):
        a, b = max(c0, lo), min(c1, hi)
        if c1 <= c0 or b <= a:
            continue
        fa = f0 + (f1 - f0) * (a - c0) / (c1 - c0)
        fb = f0 + (f1 - f0) * (b - c0) / (c1 - c0)
        total += (b - a) * (fa + fb) / 2.0
    return total


def lowest(values: dict[str, float]) -> str:
    """The gate with the smallest value (ties: the first in ``DEPLOYABLE`` order)."""
    return min(DEPLOYABLE, key=lambda name: (values[name], DEPLOYABLE.index(name)))


def matrices(raw: pd.DataFrame, adjusted: pd.DataFrame) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Each deployable gate's ``(signal, outcome)`` per trajectory and budget, as ``gates_from_tables`` builds
    them (posterior variance executes the raw aims), and each trajectory's instance; incomplete ones dropped."""
    index, budgets, raw_pred = trajectory_matrix(raw, "predicted")
    get = lambda table, column: trajectory_matrix(table, column, budgets, index)[2]  # noqa: E731
    raw_real, raw_var = get(raw, "realized"), get(raw, "post_var")
    adj_pred, adj_real = get(adjusted, "predicted"), get(adjusted, "realized")
    keep = np.all([np.isfinite(m).all(axis=1) for m in (raw_pred, raw_real, adj_pred, adj_real)], axis=0)
    gates = {"raw": (raw_pred, raw_real), "adjusted": (adj_pred, adj_real), "posterior_variance": (raw_var, raw_real)}
    instances = index.get_level_values("instance_id").to_numpy()[keep]
    return instances, {name: (sig[keep], out[keep]) for name, (sig, out) in gates.items()}


def compare(gates: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, Any]:
    """Own-range area, range-normalized area and common-range area of each deployable gate."""
    curves = {name: gate_curve(sig, out) for name, (sig, out) in gates.items()}
    ranges = {name: curve_area(curve) for name, curve in curves.items()}
    lo = max(r["c_min"] for r in ranges.values())
    hi = min(r["c_max"] for r in ranges.values())
    out: dict[str, Any] = {"common.c_lo": lo, "common.c_hi": hi}
    for name in DEPLOYABLE:
        out[f"{name}.area"] = ranges[name]["area"]
        out[f"{name}.c_min"] = ranges[name]["c_min"]
        out[f"{name}.normalized"] = ranges[name]["mean_failure"]
        out[f"{name}.common_area"] = area_between(curves[name], lo, hi)
    for reading in ("area", "normalized", "common_area"):
        name = lowest({g: out[f"{g}.{reading}"] for g in DEPLOYABLE})
        out[f"{reading}.lowest_is_posterior_variance"] = int(name == "posterior_variance")
    return out


def bootstrap_share(instances: np.ndarray, gates: dict[str, tuple[np.ndarray, np.ndarray]], resamples: int,
                    seed: int) -> dict[str, float]:
    """Share of cluster-bootstrap resamples of the test instances (all of an instance's trajectories go
    together) in which posterior variance is lowest, by range-normalized area and by common-range area."""
    rng = np.random.default_rng(seed)
    names, codes = np.unique(instances, return_inverse=True)
    rows_of = [np.flatnonzero(codes == i) for i in range(names.size)]
    norm = common = 0
    for _ in range(resamples):
        rows = np.concatenate([rows_of[i] for i in rng.integers(names.size, size=names.size)])
        v = compare({name: (sig[rows], out[rows]) for name, (sig, out) in gates.items()})
        norm += v["normalized.lowest_is_posterior_variance"]
        common += v["common_area.lowest_is_posterior_variance"]
    return {"bootstrap.normalized_share": norm / resamples, "bootstrap.common_area_share": common / resamples,
            "bootstrap.resamples": resamples}


def summary(rows: pd.DataFrame, resamples: int, seed: int) -> dict[str, Any]:
    """Every key of ``explain:results.ex6_random_gates`` from the stored rows (what verify recomputes)."""
    part = lambda name: rows[rows["request"] == name].drop(columns="request").reset_index(drop=True)  # noqa: E731
    instances, gates = matrices(part("raw"), part("adjusted"))
    out = compare(gates)
    out.update(bootstrap_share(instances, gates, resamples, seed))
    return out


def run(record: list[pd.DataFrame], resamples: int, seed: int) -> tuple[dict[str, Any], pd.DataFrame | None]:
    """Keys of ``explain:results.ex6_random_gates`` from the random-gate step's recorded rows, and the rows
    stored (the two executors' test episodes; the margin search's rows are not needed)."""
    if not record:
        return {}, None
    rows = pd.concat(record, ignore_index=True)
    rows = rows[rows["request"].isin(["raw", "adjusted"])].drop(columns="gamma").reset_index(drop=True)
    for column in ("escaped", "covered"):
        if column in rows.columns:
            rows[column] = rows[column].astype("boolean")
    return summary(rows, resamples, seed), rows
