"""The margin search laid open: mean predicted against realized failure at every gamma.

The paper's rule (Sec. IV): gamma is the largest grid value whose mean predicted failure,
over all calibration episodes and budgets, is at least the realized failure of the aims it
selects, with the set calibrated at the fixed-budget thresholds ``t_k``. The search in
``runner.calibration`` stops at the first gamma that passes; here every gamma is committed,
so the whole curve is published, and the rule is also applied to the calibration
trajectories that do not escape at the final budget (which separates "the score is
optimistic everywhere" from "a few escaped trajectories carry the optimism").
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.conformal import budget_thresholds, conformal_quantile, worst_budget_scores
from probecommit.audit.margin import GAMMA_GRID, instance_optimism, margin_candidates, optimism_margin
from probecommit.runner.calibration import calibration_scores, load_for_commit

#: Columns kept of each re-executed calibration table.
COLUMNS = ("instance_id", "repeat", "k", "status", "predicted", "realized")


def _select(table: pd.DataFrame) -> float:
    """Largest gamma with mean predicted >= mean realized (sums with the search's 1e-9 slack)."""
    ok = table[table["sum_predicted"] >= table["sum_realized"] - 1e-9]
    return float(ok["gamma"].max()) if len(ok) else float("nan")


def margin_curve(cal_run: Any, budgets: Sequence[int], alpha: float, escaped_final: pd.Series | None = None, *,
                 grid: Sequence[float] = GAMMA_GRID, chunk_instances: int | None = 48,
                 set_calibrated: bool = True) -> dict[str, Any]:
    """Per-gamma mean predicted and realized failure of the set-calibrated executor on a calibration run.

    Args:
        cal_run: Calibration run (directory or ``LoadedRun``).
        budgets: Budgets calibrated and averaged over.
        alpha: Miscoverage level of the thresholds.
        escaped_final: Per ``(instance_id, repeat)``, final-budget escape (to rerun the rule
            on the trajectories that stay covered); None skips it.
        set_calibrated: Commit at the thresholds ``t_k`` (the paper's rule); False commits at the
            run's mass ``nu`` instead (the margin an uncalibrated executor would get).

    Returns:
        ``table`` (a DataFrame: gamma, mean predicted and realized over all and over covered
        trajectories), ``gamma`` and ``gamma_covered_only`` (the rule on each), the
        thresholds ``t_k``, the simultaneous ``t`` and the distribution-free margin.
    """
    cal = load_for_commit(cal_run, True, None, chunk_instances, budgets)
    scores = calibration_scores(cal)
    t_k = budget_thresholds(scores, alpha, budgets)
    t_sim = conformal_quantile(worst_budget_scores(scores, budgets).to_numpy(), alpha)
    gammas = margin_candidates(grid)
    sets = t_k if set_calibrated else cal.nu
    tables = cal.commit((t_k, None), *[(sets, g) for g in gammas], keep=[COLUMNS] * (len(gammas) + 1), final=True)
    set_only = tables[0]
    optimism = instance_optimism(set_only, budgets)
    rows = []
    instances = np.sort(set_only["instance_id"].astype(str).unique())
    pred_sums, real_sums = [], []
    for gamma, table in zip(gammas, tables[1:]):
        ok = table[(table["status"] == "ok") & table["k"].isin(list(budgets))]
        row = {"gamma": gamma, "n": int(len(ok)), "mean_predicted": float(ok["predicted"].mean()),
               "mean_realized": float(ok["realized"].mean()), "sum_predicted": float(ok["predicted"].sum()),
               "sum_realized": float(ok["realized"].sum())}
        for k in budgets:
            at = ok[ok["k"] == k]
            row[f"sum_predicted_k{k}"], row[f"sum_realized_k{k}"] = float(at["predicted"].sum()), float(at["realized"].sum())
        per = ok.groupby(ok["instance_id"].astype(str))[["predicted", "realized"]].sum().reindex(instances, fill_value=0.0)
        pred_sums.append(per["predicted"].to_numpy(float))
        real_sums.append(per["realized"].to_numpy(float))
        if escaped_final is not None:
            label = pd.MultiIndex.from_frame(ok[["instance_id", "repeat"]]).map(escaped_final.to_dict().get)
            cov = ok[~np.asarray(label, dtype=bool)]
            row.update(mean_predicted_covered=float(cov["predicted"].mean()), mean_realized_covered=float(cov["realized"].mean()),
                       sum_predicted_covered=float(cov["predicted"].sum()), sum_realized_covered=float(cov["realized"].sum()))
        rows.append(row)
    table = pd.DataFrame(rows)
    per_budget = {k: _select(pd.DataFrame({"gamma": table["gamma"], "sum_predicted": table[f"sum_predicted_k{k}"],
                                           "sum_realized": table[f"sum_realized_k{k}"]})) for k in budgets}
    x = cal.loaded.instances.set_index(cal.loaded.instances["instance_id"].astype(str))["true_x_hole"]
    out = {"x_hole": x.reindex(instances).to_numpy(float), "gamma_per_budget": per_budget, "instance_sums": (np.array(gammas), np.array(pred_sums), np.array(real_sums)),
           "scores": scores, "table": table, "gamma": _select(table), "thresholds": {int(k): float(v) for k, v in t_k.items()},
           "simultaneous_threshold": float(t_sim), "distribution_free_margin": float(optimism_margin(optimism, alpha)),
           "worst_budget_optimism": optimism.max(axis=1), "optimism": optimism, "instances": instances}
    if escaped_final is not None:
        covered = pd.DataFrame({"gamma": table["gamma"], "sum_predicted": table["sum_predicted_covered"],
                                "sum_realized": table["sum_realized_covered"]})
        out["gamma_covered_only"] = _select(covered)
    final = max(budgets)
    out["scores_final"] = scores[final]
    return out
