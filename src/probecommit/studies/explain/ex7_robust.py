"""The contamination mixture over fresh MuJoCo draws (E71, E72; ``docs/decisions.md``, ex7).

Why: our development tuning picks the mixture weight 0.05 where the paper's picks 0.01 (T42),
and with the right model our mixture costs no failure where the paper's costs 0.065 (T44). E31 and
E46 resampled our development instances and the filter's seed; neither draws new instances. Here
the frozen protocol is rerun on fresh instance draws of the same generators (only the split name
changes, so each draw is a disjoint instance and tap-noise stream), on MuJoCo:

* E71: fresh 24-instance development draws, each tuned over the paper's epsilon grid by the frozen
  rule (lowest final-budget failure, ties to the first grid value, :func:`~probecommit.studies.robust.mark_chosen`);
* E72: fresh 96-instance draws of the fault harness's base run (corrected model), each replayed with
  the mixture at the paper's epsilon: the paired cost, and the share of aims it changes (a bound on it).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.replay_final import replay_at
from probecommit.studies.explain.runs import _run
from probecommit.studies.robust import final_failure, final_rows, mark_chosen, robust_candidates


def tune_at_final(run: Any, grid: dict[str, list[tuple[float, dict[str, Any]]]]) -> pd.DataFrame:
    """``tune_robust_filters(run, grid)`` without its ``belief`` column: a candidate's failure reads only the final
    budget, so each replay commits only it (``replay_at``: the same rows there; committing the other seven budgets
    was half of each dev draw's replay CPU, issue 42)."""
    from probecommit.runner.replay import committed_budgets

    k = max(committed_budgets(run.config))
    rows = [{"family": family, "value": value, "failure": final_failure(replay_at(run, {"belief": belief}, k))}
            for family, candidates in grid.items() for value, belief in candidates]
    return mark_chosen(pd.DataFrame(rows, columns=["family", "value", "failure"]))


def dev_draw_table(protocol: Any, runs: Any, count: int, workers: int = 1) -> pd.DataFrame:
    """Per fresh development draw and epsilon: final-budget failure and whether the frozen rule chooses it."""
    r = protocol.robust
    grid = {"mixture": robust_candidates(r.temperatures, r.epsilons, r.rejuvenation, r.mixture_range)["mixture"]}
    parts = []
    for i in range(count):
        split = f"dev_draw_{i:02d}"
        run = _run(protocol.run_config(split, "development", split, "random"), runs / split, workers)
        table = tune_at_final(run, grid)
        parts.append(table.assign(draw=split))
    return pd.concat(parts, ignore_index=True)[["draw", "family", "value", "failure", "chosen"]]


def dev_draw_keys(table: pd.DataFrame, paper: float, ours: float) -> dict[str, Any]:
    """E71's keys from :func:`dev_draw_table`'s rows: the share of draws choosing each epsilon, the paper's and ours."""
    chosen = table[table["chosen"]].set_index("draw")["value"]
    out: dict[str, Any] = {"count": int(chosen.size), "share_paper": float(np.mean(np.isclose(chosen, paper))),
                           "share_ours": float(np.mean(np.isclose(chosen, ours)))}
    for value, part in table.groupby("value"):
        out[f"eps_{value:g}.share_chosen"] = float(np.mean(np.isclose(chosen, value)))
        out[f"eps_{value:g}.failure_mean"] = float(part["failure"].mean())
    return out


def harness_draw_table(protocol: Any, runs: Any, mixture: dict[str, Any], count: int, workers: int = 1) -> pd.DataFrame:
    """Per fresh draw of the harness's base run (corrected model): final-budget failure without and with the
    mixture (same stored probes, paired) and the share of aims the mixture changes."""
    k, rows = protocol.budgets["random"], []
    for i in range(count):
        split = f"harness_draw_{i:02d}"
        run = harness_draw(protocol, runs, i, workers)
        right = _final(final_rows(run.episodes), k)
        mixed = _final(final_rows(replay_at(run, {"belief": mixture}, k)), k)  # only budget k committed
        rows.append({"draw": split, "right": float(right["realized"].mean()), "mixed": float(mixed["realized"].mean()),
                     "changed": float((right["action"].to_numpy() != mixed["action"].to_numpy()).mean())})
    return pd.DataFrame(rows, columns=["draw", "right", "mixed", "changed"])


def harness_draw(protocol: Any, runs: Any, i: int, workers: int = 1) -> Any:
    """Fresh draw ``i`` of the fault harness's base run (split ``harness_draw_<i>``, corrected model, random
    probes, the harness's seed offset), run once under ``runs`` and loaded (E72's and ex37's E213's)."""
    split = f"harness_draw_{i:02d}"
    config = protocol.run_config(split, "B", split, "random", boundary="corrected", seed_offset=protocol.faults.seed_offset)
    return _run(config, runs / split, workers)


def _final(rows: pd.DataFrame, k: int) -> pd.DataFrame:
    return rows[rows["k"] == k].sort_values(["instance_id", "repeat"]).reset_index(drop=True)


def harness_draw_keys(table: pd.DataFrame) -> dict[str, Any]:
    """E72's keys from :func:`harness_draw_table`'s rows."""
    cost = table["mixed"].to_numpy(float) - table["right"].to_numpy(float)
    out: dict[str, Any] = {"count": int(len(table))}
    for name, values in (("paired_cost", cost), ("right.failure", table["right"].to_numpy(float)),
                         ("changed_aims", table["changed"].to_numpy(float))):
        out.update({f"{name}.mean": float(values.mean()), f"{name}.min": float(values.min()),
                    f"{name}.max": float(values.max())})
    return out


#: The per-draw rows E71's and E72's keys come from (``explain/results/``).
STORED_DEV, STORED_HARNESS = "ex7_dev_draws.parquet", "ex7_harness_draws.parquet"


def run(job: Any) -> None:
    """Fill ``explain:results.ex7_robust`` (E71, E72)."""
    from probecommit.studies.paper_values import value

    p, cfg, r = job.p, job.cfg, job.p.robust
    quick = "_quick" if job.quick else ""
    out = job.res["ex7_robust"]
    paper_eps = value("T42-robust-chosen.mixture")
    ours = job.insertion_results()["robust"]["chosen"]["mixture"]
    dev = dev_draw_table(p, job.runs, cfg[f"ex7_dev_draws{quick}"], job.workers)
    out.update({f"dev_draws.mixture.{k}": v for k, v in dev_draw_keys(dev, paper_eps, ours).items()})
    mixture = {"likelihood": "mixture", "epsilon": paper_eps, "mixture_low": r.mixture_range[0],
               "mixture_high": r.mixture_range[1]}
    harness = harness_draw_table(p, job.runs, mixture, cfg[f"ex7_harness_draws{quick}"], job.workers)
    out.update({f"harness_draws.mixture.{k}": v for k, v in harness_draw_keys(harness).items()})
    job.stored[STORED_DEV], job.stored[STORED_HARNESS] = dev, harness
