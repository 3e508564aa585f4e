"""The explain target's calibration rows per instance, and the margin and threshold keys that read them.

Why: the validation-tuned margins, the conformal thresholds, their cluster-bootstrap intervals and
shares, and the margin split by stratum are functions of a few numbers per calibration instance
(its worst-repeat coverage score and mean optimism per budget, its sums of predicted and realized
failure at each margin candidate, where its hole is). Those come from re-commits a publication cannot
hold; the explain step stores them (``MARGIN_INSTANCES``, ``MARGIN_SUMS``, and the margin curve's
rule sums in ``margin_per_gamma.parquet``) and fills the keys by calling :func:`margin_rule_keys` on
the very tables it writes; ``verify`` calls it on the stored copy, so the keys agree to the last bit.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
import pandas as pd

#: Per (schedule, instance): hole position, worst-repeat score and mean optimism per budget, final escapes.
MARGIN_INSTANCES = "margin_instances.parquet"
#: Per (schedule, margin candidate, instance): the sums of predicted and realized failure the rule compares.
MARGIN_SUMS = "margin_instance_sums.parquet"
#: The uncalibrated (``nu``) executor's margin curve, stored in ``margin_per_gamma.parquet`` under this label.
NU_EXECUTOR = "ours_nu_executor"


def instance_table(label: str, curve: Mapping[str, Any], escaped_final: pd.Series) -> pd.DataFrame:
    """One schedule's per-instance rows from ``margin.margin_curve``'s result and the final-budget escapes
    per ``(instance_id, repeat)``: ``x_hole``, ``score_k<k>``, ``optimism_k<k>``, ``escaped_final``, ``episodes_final``."""
    scores = curve["scores"].copy()
    scores.index = scores.index.astype(str)
    optimism = curve["optimism"].copy()
    optimism.index = optimism.index.astype(str)
    escaped = escaped_final.astype(int).groupby(escaped_final.index.get_level_values(0).astype(str))
    names = np.sort(np.unique(np.concatenate([scores.index.to_numpy(str), optimism.index.to_numpy(str),
                                              np.asarray(curve["instances"], dtype=str)])))
    table = pd.DataFrame({"schedule": label, "instance_id": names})
    x = pd.Series(curve["x_hole"], index=np.asarray(curve["instances"], dtype=str))
    table["x_hole"] = x.reindex(names).to_numpy(float)
    for k in scores.columns:
        table[f"score_k{int(k)}"] = scores[k].reindex(names).to_numpy(float)
    for k in optimism.columns:
        table[f"optimism_k{int(k)}"] = optimism[k].reindex(names).to_numpy(float)
    table["escaped_final"] = escaped.sum().reindex(names, fill_value=0).to_numpy("int64")
    table["episodes_final"] = escaped.count().reindex(names, fill_value=0).to_numpy("int64")
    return table


def sums_table(label: str, curve: Mapping[str, Any]) -> pd.DataFrame:
    """One schedule's per-instance sums at every margin candidate (the search's order), long."""
    gammas, pred, real = curve["instance_sums"]
    names = np.asarray(curve["instances"], dtype=str)
    return pd.DataFrame({"schedule": label, "gamma": np.repeat(np.asarray(gammas, float), names.size),
                         "instance_id": np.tile(names, len(gammas)), "sum_predicted": np.asarray(pred, float).ravel(),
                         "sum_realized": np.asarray(real, float).ravel()})


def _by_budget(rows: pd.DataFrame, prefix: str) -> pd.DataFrame:
    """``<prefix><k>`` columns as an instances x budgets frame (columns the integer budgets, NaN rows kept)."""
    cols = [c for c in rows.columns if c.startswith(prefix) and rows[c].notna().any()]
    out = pd.DataFrame({int(c[len(prefix):]): rows[c].to_numpy(float) for c in cols}, index=rows["instance_id"].to_numpy(str))
    return out[sorted(out.columns)]


def _select(gammas: pd.Series, predicted: pd.Series, realized: pd.Series) -> float:
    """``margin._select``: the largest gamma whose predicted sum reaches the realized sum (1e-9 slack)."""
    from probecommit.studies.explain.margin import _select as select

    return select(pd.DataFrame({"gamma": gammas, "sum_predicted": predicted, "sum_realized": realized}))


def margin_rule_keys(curves: pd.DataFrame, instances: pd.DataFrame, sums: pd.DataFrame, *, alpha: float, edge: float,
                     boot: Mapping[str, int]) -> dict[str, dict[str, Any]]:
    """``margin_per_gamma`` (each schedule's margin by the rule, on covered trajectories, per budget, by stratum,
    its bootstrap interval and share at the paper's value; the ``nu`` executor's margin) and ``thresholds``
    (t_k, t, the distribution-free margin, their intervals and shares) from the stored rows."""
    out: dict[str, dict[str, Any]] = {"margin_per_gamma": {}, "thresholds": {}}
    for label, curve in curves.groupby("schedule", sort=False):
        if label == NU_EXECUTOR:
            continue
        _schedule_keys(str(label), curve.reset_index(drop=True), instances[instances["schedule"] == label],
                       sums[sums["schedule"] == label], alpha, edge, boot, out)
    nu = curves[curves["schedule"] == NU_EXECUTOR].reset_index(drop=True)
    if len(nu):
        g = out["margin_per_gamma"]
        g["ours.gamma_nu_executor"] = _select(nu["gamma"], nu["sum_predicted"], nu["sum_realized"])
        g["ours.optimism_at_gamma_1_nu_executor"] = float(nu.iloc[0].mean_realized - nu.iloc[0].mean_predicted)
    return out


def _schedule_keys(label: str, curve: pd.DataFrame, rows: pd.DataFrame, sums: pd.DataFrame, alpha: float, edge: float,
                   boot: Mapping[str, int], out: dict[str, dict[str, Any]]) -> None:
    from probecommit.audit.conformal import budget_thresholds, conformal_quantile, worst_budget_scores
    from probecommit.audit.margin import optimism_margin
    from probecommit.studies.paper_values import value as paper_value

    g, t = out["margin_per_gamma"], out["thresholds"]
    rows = rows.sort_values("instance_id").reset_index(drop=True)
    scores, optimism = _by_budget(rows, "score_k"), _by_budget(rows, "optimism_k")
    budgets = [int(k) for k in scores.columns]
    k = max(budgets)
    t_k = budget_thresholds(scores, alpha, budgets)
    g[f"{label}.gamma"] = _select(curve["gamma"], curve["sum_predicted"], curve["sum_realized"])
    g[f"{label}.gamma_covered_only"] = _select(curve["gamma"], curve["sum_predicted_covered"], curve["sum_realized_covered"])
    g[f"{label}.escaped_share_cal"] = float(rows["escaped_final"].sum() / rows["episodes_final"].sum())
    t[f"{label}.t_{k}"] = t_k[k]
    t[f"{label}.simultaneous"] = float(conformal_quantile(worst_budget_scores(scores, budgets).to_numpy(), alpha))
    t[f"{label}.distribution_free_margin"] = float(optimism_margin(optimism.dropna(how="all"), alpha))
    t[f"{label}.share_scores_final_above_paper_t"] = float((scores[k] > paper_value("T02-t5-cover.t5")).mean())
    t[f"{label}.share_scores_final_escaped"] = float((scores[k] > 1.0).mean())
    worst = optimism.dropna(how="all").max(axis=1)
    t[f"{label}.share_worst_optimism_above_paper_df"] = float((worst > paper_value("T04-distribution-free-margin.cover")).mean())
    for kk in budgets:
        g[f"{label}.gamma_at_k{kk}"] = _select(curve["gamma"], curve[f"sum_predicted_k{kk}"], curve[f"sum_realized_k{kk}"])
    _intervals(label, curve, rows, sums, scores, worst, t_k, alpha, edge, boot, out)


def _intervals(label: str, curve: pd.DataFrame, rows: pd.DataFrame, sums: pd.DataFrame, scores: pd.DataFrame,
               worst: pd.Series, t_k: dict[int, float], alpha: float, edge: float, boot: Mapping[str, int],
               out: dict[str, dict[str, Any]]) -> None:
    """Cluster-bootstrap intervals of gamma, t_k, the simultaneous t and the distribution-free margin (how far
    a quantile of the calibration instances moves with the draw alone), and the margin by stratum."""
    from probecommit.audit.stats import percentile_interval, resample_counts
    from probecommit.studies.explain.stats import conformal_quantile_draws, margin_draws
    from probecommit.studies.paper_values import value as paper_value

    g, t = out["margin_per_gamma"], out["thresholds"]
    k = max(int(c) for c in scores.columns)
    gammas = pd.unique(sums["gamma"].to_numpy(float))
    names = np.sort(pd.unique(sums["instance_id"].to_numpy(str)))
    pred = sums.pivot(index="gamma", columns="instance_id", values="sum_predicted").reindex(index=gammas, columns=names)
    real = sums.pivot(index="gamma", columns="instance_id", values="sum_realized").reindex(index=gammas, columns=names)
    pred, real = pred.to_numpy(float), real.to_numpy(float)
    order = np.sort(scores.index.to_numpy(str))
    counts = resample_counts(order.size, int(boot["resamples"]), int(boot["seed"]))
    gamma = g[f"{label}.gamma"]
    draws = margin_draws(gammas, pred, real, counts)
    g[f"{label}.gamma_interval"] = [gamma, *percentile_interval(draws)]
    g[f"{label}.share_resamples_gamma_at_least_paper"] = float(np.mean(draws >= paper_value("T03-margin.cover") - 1e-12))
    t_draws = conformal_quantile_draws(scores.loc[order, k].to_numpy(float), counts, alpha)
    t[f"{label}.t_{k}_interval"] = [t_k[k], *percentile_interval(t_draws)]
    t[f"{label}.share_resamples_t_{k}_at_most_paper"] = float(np.mean(t_draws <= paper_value("T02-t5-cover.t5")))
    df_draws = conformal_quantile_draws(worst.reindex(order).to_numpy(float), counts, alpha)
    t[f"{label}.distribution_free_margin_interval"] = [t[f"{label}.distribution_free_margin"], *percentile_interval(df_draws)]
    t[f"{label}.share_resamples_df_at_least_paper"] = float(np.mean(df_draws >= paper_value("T04-distribution-free-margin.cover")))
    x = rows.set_index(rows["instance_id"].astype(str))["x_hole"].reindex(names).to_numpy(float)
    beyond = np.abs(x) > edge
    share = (10.0 - edge) / 10.0  # the +-10 mm box's share beyond the edge
    weights = np.where(beyond, share / max(beyond.mean(), 1e-12), (1 - share) / max((~beyond).mean(), 1e-12))
    g[f"{label}.gamma_standardized"] = float(margin_draws(gammas, pred, real, weights[None, :])[0])
    g[f"{label}.gamma_inside"] = float(margin_draws(gammas, pred, real, (~beyond).astype(float)[None, :])[0])
    g[f"{label}.gamma_beyond"] = float(margin_draws(gammas, pred, real, beyond.astype(float)[None, :])[0])


#: The explain step's re-executed commits (``runner.calibration.Recorder``, ``insertion.store_commits``):
#: ``calibration`` ``gates_random`` (the random-probe gates) and ``paper_schedule`` (Table IV under the paper's schedule).
COMMITS = "commits.parquet"
#: The episodes of the explain step's own runs those calibrations read (``run``: ``paper_B_cal``, ``paper_B_test``,
#: ``B_cal_random_corrected``), the columns the insertion study stores of its runs.
EPISODES = "episodes.parquet"
#: The stored runs of ``EPISODES``.
PAPER_CAL, PAPER_TEST, RANDOM_CORRECTED = "paper_B_cal", "paper_B_test", "B_cal_random_corrected"


def random_gate_keys(result: Any) -> dict[str, dict[str, Any]]:
    """``missing.gate_area_random.*``, ``missing.gate_mean_failure_random.*`` and ``committed_pool.random.*`` from a
    ``GatesResult`` on the random-probe calibration and test runs (``gates`` in the explain step,
    ``gates_from_commits`` of the stored rows in verify)."""
    from probecommit.studies.explain.pool import gate_pools

    pools = gate_pools(result)
    m: dict[str, Any] = {}
    areas = {name: pools.get(f"{name}.area", float("nan")) for name in ("raw", "adjusted", "posterior_variance")}
    m.update({f"gate_area_random.{name}": area for name, area in areas.items()})
    m["gate_area_random.lowest_is_posterior_variance"] = int(min(areas, key=areas.get) == "posterior_variance")
    # Areas span each gate's own attainable range; the mean failure over it compares them on equal terms.
    means = {name: pools.get(f"{name}.mean_failure", float("nan")) for name in areas}
    m.update({f"gate_mean_failure_random.{name}": v for name, v in means.items()})
    m["gate_mean_failure_random.lowest_is_posterior_variance"] = int(min(means, key=means.get) == "posterior_variance")
    return {"missing": m, "committed_pool": {f"random.{k}": v for k, v in pools.items()}}


def paper_calibration_keys(cal: Any) -> dict[str, dict[str, Any]]:
    """Table IV's rows and the cost of calibration under the paper's schedule, and its margin, from a
    ``CalibrationResult`` (``calibrate`` in the explain step, ``calibration_from_tables`` in verify)."""
    from probecommit.studies.explain.study import COST_LABELS

    pool = {f"schedule.B_test.paper_schedule.cost_table.{str(row['setting']).replace(' + ', '_').replace(' ', '_')}":
            [row["failure"], row["failure_lo"], row["failure_hi"]] for row in cal.cost.to_dict("records")}
    missing = {f"cost_of_calibration_paper_schedule.{COST_LABELS[(row['baseline'], row['treatment'])]}":
               [row["difference"], row["lo"], row["hi"]] for row in cal.cost_differences.to_dict("records")}
    return {"committed_pool": pool, "missing": missing, "margin_per_gamma": {"paper_schedule.gamma_calibrate": cal.margin.gamma}}


def threshold_keys(runs: Mapping[str, pd.DataFrame], random_budgets: list[int], cover_budgets: list[int],
                   alpha: float) -> dict[str, dict[str, Any]]:
    """The simultaneous thresholds of the random-probe calibration run (as stored and under the corrected
    boundary) and of the corrected cover calibration run, from each run's Probe-Robust episodes."""
    from probecommit.audit.conformal import simultaneous_threshold

    probe = {name: rows[(rows["method"] == "probe_robust") & (rows["status"] == "ok")] for name, rows in runs.items()}
    return {"missing": {"simultaneous_threshold_random_corrected":
                        simultaneous_threshold(probe[RANDOM_CORRECTED], random_budgets, alpha)},
            "thresholds": {"simultaneous_random_original_recomputed":
                           simultaneous_threshold(probe["B_cal_random"], random_budgets, alpha),
                           "simultaneous_cover_corrected_recomputed":
                           simultaneous_threshold(probe["B_cal_cover_corrected"], cover_budgets, alpha)}}
