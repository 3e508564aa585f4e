"""Commit gates with first-passage commitment over nested budgets (paper Sec. VI).

A trajectory of nested budgets ``k_1 < ... < k_K`` (one instance, one repeat)
commits at the FIRST budget whose signal is ``<= tau``; one that never passes does
not commit. Sweeping ``tau`` over every distinct signal value traces failure among
committed trajectories against the commit rate. Signals:

- ``raw``: the scenario failure fraction (``predicted``) of the uncalibrated
  ``nu = 0.8`` executor, whose aims are then executed;
- ``adjusted``: ``predicted`` of the calibrated + margin executor, with its aims;
- ``posterior_variance``: ``post_var`` (it makes no probability claim);
- ``oracle``: the realized outcome itself (hindsight, non-deployable).

Curves are computed exactly by an event sweep, not by evaluating every threshold:
a trajectory's stopping budget changes only at its running-minimum records.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.io import ok_episodes

#: The commit rate at which the paper reads the committed pool (60%).
DEFAULT_TARGET_RATE = 0.6


@dataclass
class GateSignal:
    """One gate: a signal per trajectory and budget and the outcome of committing there.

    Attributes:
        name: Label (``raw``, ``adjusted``, ``posterior_variance``, ``oracle``).
        signal: ``[T, K]``; NaN never passes.
        outcome: ``[T, K]`` realized failure (or loss) of the executor's aim at each budget.
        claim: ``[T, K]`` the failure score the executor claims (None if the signal
            makes no probability claim).
        deployable: False for the hindsight oracle.
    """

    name: str
    signal: np.ndarray
    outcome: np.ndarray
    claim: np.ndarray | None = None
    deployable: bool = True


@dataclass
class GatesResult:
    """Gate curves and their summary.

    Attributes:
        curves: ``signal, tau, n_committed, commit_rate, failure`` per sweep point.
        summary: One row per signal: attainable range, area, and the pool at the
            operating point nearest the target commit rate.
        budgets: The nested budgets used.
        n_trajectories: Trajectories evaluated.
        n_dropped: Trajectories dropped (a failed or missing episode at some budget).
        info: Free-form provenance (thresholds, margin) filled by the caller.
    """

    curves: pd.DataFrame
    summary: pd.DataFrame
    budgets: list[int]
    n_trajectories: int
    n_dropped: int = 0
    info: dict = field(default_factory=dict)


def trajectory_matrix(episodes: pd.DataFrame, column: str, budgets: Sequence[int] | None = None,
                      index: pd.MultiIndex | None = None) -> tuple[pd.MultiIndex, list[int], np.ndarray]:
    """Pivot one column to trajectories ``(instance_id, repeat)`` x budgets.

    Failed episodes become NaN.

    Returns:
        ``(index, budgets, values[T, K])``.
    """
    df = ok_episodes(episodes)
    if column not in df.columns:
        raise ValueError(f"episode table has no '{column}' column")
    if budgets is None:
        budgets = sorted(int(k) for k in df["k"].unique() if k >= 1)
    budgets = sorted(int(k) for k in budgets)
    df = df.loc[df["k"].isin(budgets)]
    if df.duplicated(["instance_id", "repeat", "k"]).any():
        raise ValueError("gate tables need one episode per (instance_id, repeat, k); filter method/variant first")
    wide = df.set_index(["instance_id", "repeat", "k"])[column].astype(float).unstack("k")
    wide = wide.reindex(columns=budgets)
    if index is not None:
        wide = wide.reindex(index)
    return wide.index, budgets, wide.to_numpy(dtype=float)


def first_passage(signal: np.ndarray, tau: float) -> np.ndarray:
    """Index of the first budget whose signal is ``<= tau``, ``-1`` where none is.

    Args:
        signal: ``[T, K]`` signal per trajectory and nested budget (NaN never passes).
        tau: Threshold.

    Returns:
        ``[T]`` budget indices.
    """
    passes = np.asarray(signal, dtype=float) <= tau
    return np.where(passes.any(axis=1), np.argmax(passes, axis=1), -1)


def gate_curve(signal: np.ndarray, outcome: np.ndarray) -> pd.DataFrame:
    """Failure among committed vs commit rate for every distinct threshold.

    For each distinct finite signal value ``tau`` (ascending), trajectories commit
    at their first budget with signal ``<= tau``. Computed by an event sweep: as
    ``tau`` rises past a running-minimum record of a trajectory, its stopping
    budget moves to that record's budget (or it starts committing).

    Args:
        signal: ``[T, K]``.
        outcome: ``[T, K]`` outcome of committing at each budget.

    Returns:
        Columns ``tau``, ``n_committed``, ``commit_rate``, ``failure`` (mean
        outcome among committed), ``n_failed_committed`` (sum of outcomes).
    """
    s = np.where(np.isnan(signal), np.inf, np.asarray(signal, dtype=float))
    y = np.asarray(outcome, dtype=float)
    n_traj, n_k = s.shape
    prev_min = np.concatenate([np.full((n_traj, 1), np.inf), np.minimum.accumulate(s, axis=1)[:, :-1]], axis=1)
    record = (s < prev_min) & np.isfinite(s)
    # Next record after k (a smaller value at a later budget): the stop just below this tau.
    rec_idx = np.where(record, np.arange(n_k)[None, :], n_k)
    suffix = np.minimum.accumulate(rec_idx[:, ::-1], axis=1)[:, ::-1]
    nxt = np.concatenate([suffix[:, 1:], np.full((n_traj, 1), n_k)], axis=1)
    t_idx, k_idx = np.nonzero(record)
    nk = nxt[t_idx, k_idx]
    last = nk == n_k
    y_pad = np.concatenate([y, np.zeros((n_traj, 1))], axis=1)
    d_commit = last.astype(float)
    d_fail = y[t_idx, k_idx] - np.where(last, 0.0, y_pad[t_idx, nk])
    v = s[t_idx, k_idx]
    order = np.argsort(v, kind="stable")
    v, d_commit, d_fail = v[order], d_commit[order], d_fail[order]
    n_c = np.cumsum(d_commit)
    n_f = np.cumsum(d_fail)
    # Evaluate at every distinct finite signal value (non-record values repeat the
    # state of the last record below them): the state after all events <= tau.
    tau = np.unique(s[np.isfinite(s)])
    pos = np.searchsorted(v, tau, side="right") - 1  # >= 0: the smallest value is always a record
    n_c, n_f = n_c[pos], n_f[pos]
    with np.errstate(invalid="ignore", divide="ignore"):
        failure = np.where(n_c > 0, n_f / np.maximum(n_c, 1), np.nan)
    return pd.DataFrame({"tau": tau, "n_committed": np.rint(n_c).astype(int), "commit_rate": n_c / max(n_traj, 1),
                         "failure": failure, "n_failed_committed": n_f})


def curve_area(curve: pd.DataFrame) -> dict[str, float]:
    """Area under failure-vs-commit-rate over the curve's attainable range.

    The points are taken in threshold order (commit rate non-decreasing) and
    joined by straight lines (trapezoid rule); a threshold step that moves stops
    without changing the commit rate is a vertical segment and adds nothing. The
    range is ``[c_min, c_max]``: the commit rates of the smallest and largest
    thresholds; nothing is extrapolated outside it.

    Returns:
        ``area`` (the integral), ``c_min``, ``c_max`` and ``mean_failure``
        (area divided by the range width; NaN for a single point).
    """
    c = curve["commit_rate"].to_numpy(float)
    f = curve["failure"].to_numpy(float)
    if c.size == 0:
        return {"area": np.nan, "c_min": np.nan, "c_max": np.nan, "mean_failure": np.nan}
    area = float(np.sum(np.diff(c) * (f[1:] + f[:-1]) / 2.0)) if c.size > 1 else 0.0
    width = float(c[-1] - c[0])
    return {"area": area, "c_min": float(c[0]), "c_max": float(c[-1]),
            "mean_failure": area / width if width > 0 else np.nan}


def operating_point(curve: pd.DataFrame, target_rate: float = DEFAULT_TARGET_RATE) -> pd.Series | None:
    """The sweep point whose commit rate is nearest ``target_rate``.

    Ties in distance go to the lower commit rate, then to the smallest threshold
    reaching that rate (the first ``tau`` at which it is attained).
    """
    if curve.empty:
        return None
    dist = np.round(np.abs(curve["commit_rate"].to_numpy(float) - target_rate), 12)
    cand = curve.assign(_d=dist).sort_values(["_d", "commit_rate", "tau"], kind="stable")
    return cand.iloc[0].drop(labels="_d")


def evaluate_gates(signals: Iterable[GateSignal], escaped_final: np.ndarray, *,
                   target_rate: float = DEFAULT_TARGET_RATE, budgets: Sequence[int] = ()) -> GatesResult:
    """Sweep every gate, integrate its curve and read its pool at the target commit rate.

    Args:
        signals: Gates over the same ``T`` trajectories and ``K`` budgets.
        escaped_final: ``[T]`` truth outside the particle hull at the final budget.
        target_rate: Commit rate of the operating point (about 60% in the paper).
        budgets: Budget labels (for the result only).

    Returns:
        Curves and a summary with, per signal: ``c_min``, ``c_max``, ``area``,
        ``mean_failure``, and at the operating point ``tau``, ``commit_rate``,
        ``n_committed``, ``escaped_committed``, ``n_rejected``,
        ``escaped_rejected``, ``claimed`` (mean claimed score at each committed
        trajectory's own stopping budget; NaN when the signal claims nothing)
        and ``realized`` (failure among committed).
    """
    escaped_final = np.asarray(escaped_final, dtype=bool)
    curves, rows = [], []
    n_traj = escaped_final.size
    for g in signals:
        curve = gate_curve(g.signal, g.outcome)
        curves.append(curve.assign(signal=g.name))
        row = {"signal": g.name, "deployable": g.deployable, **curve_area(curve)}
        op = operating_point(curve, target_rate)
        if op is not None:
            stop = first_passage(g.signal, float(op["tau"]))
            committed = stop >= 0
            rows_t = np.flatnonzero(committed)
            claim = np.nan
            if g.claim is not None and committed.any():
                claim = float(np.mean(g.claim[rows_t, stop[committed]]))
            realized = float(np.mean(g.outcome[rows_t, stop[committed]])) if committed.any() else np.nan
            row.update(tau=float(op["tau"]), commit_rate=float(committed.mean()), n_committed=int(committed.sum()),
                       escaped_committed=int(escaped_final[committed].sum()), n_rejected=int((~committed).sum()),
                       escaped_rejected=int(escaped_final[~committed].sum()), claimed=claim, realized=realized)
        rows.append(row)
    curves_df = pd.concat(curves, ignore_index=True) if curves else pd.DataFrame()
    if not curves_df.empty:
        curves_df = curves_df[["signal", "tau", "n_committed", "commit_rate", "failure", "n_failed_committed"]]
    return GatesResult(curves_df, pd.DataFrame(rows), list(budgets), n_traj)


def gates_from_tables(raw: pd.DataFrame, adjusted: pd.DataFrame | None = None, *,
                      budgets: Sequence[int] | None = None, target_rate: float = DEFAULT_TARGET_RATE,
                      post_var_executor: str = "raw") -> GatesResult:
    """The paper's four gates from the test episode tables of two executors.

    Args:
        raw: Test episodes of the uncalibrated ``nu = 0.8`` executor (one method/variant).
        adjusted: Test episodes of the calibrated + margin executor (same
            trajectories); None skips the adjusted gate.
        budgets: Nested budgets (default: every ``k >= 1`` of ``raw``).
        target_rate: Operating-point commit rate.
        post_var_executor: Whose aims the posterior-variance gate executes,
            ``"raw"`` or ``"adjusted"`` (the belief, hence ``post_var``, is the same).

    Returns:
        The gates result. Trajectories with a failed or missing episode at any
        budget (in either table) are dropped and counted in ``n_dropped``.
    """
    index, budgets, raw_pred = trajectory_matrix(raw, "predicted", budgets)
    _, _, raw_real = trajectory_matrix(raw, "realized", budgets, index)
    _, _, raw_var = trajectory_matrix(raw, "post_var", budgets, index) if "post_var" in raw.columns else (None, None, None)
    _, _, escaped = trajectory_matrix(raw, "escaped", budgets, index)
    mats = [raw_pred, raw_real, escaped]
    if adjusted is not None:
        _, _, adj_pred = trajectory_matrix(adjusted, "predicted", budgets, index)
        _, _, adj_real = trajectory_matrix(adjusted, "realized", budgets, index)
        mats += [adj_pred, adj_real]
    keep = np.all([np.isfinite(m).all(axis=1) for m in mats], axis=0)
    n_dropped = int((~keep).sum())
    # Trajectories with only failed rows (e.g. probing failed) never reach the matrices.
    if "status" in raw.columns:
        bad = raw.loc[raw["status"] == "failed", ["instance_id", "repeat"]].drop_duplicates()
        n_dropped += int((~pd.MultiIndex.from_frame(bad).isin(index)).sum()) if len(bad) else 0
    sel = lambda m: None if m is None else m[keep]  # noqa: E731
    escaped_final = sel(escaped)[:, -1].astype(bool)
    signals = [GateSignal("raw", sel(raw_pred), sel(raw_real), sel(raw_pred))]
    if adjusted is not None:
        signals.append(GateSignal("adjusted", sel(adj_pred), sel(adj_real), sel(adj_pred)))
    if raw_var is not None:
        outcome = sel(adj_real) if (post_var_executor == "adjusted" and adjusted is not None) else sel(raw_real)
        signals.append(GateSignal("posterior_variance", sel(raw_var), outcome, None))
    signals.append(GateSignal("oracle", sel(raw_real), sel(raw_real), None, deployable=False))
    result = evaluate_gates(signals, escaped_final, target_rate=target_rate, budgets=budgets)
    result.n_dropped = n_dropped
    return result
