"""The explain target's stored rows and the summaries that read them: one function per table, shared.

Why: most published explain keys are summaries (a curve's cells, min / max / mean over fresh draws)
of rows that come from re-commits and replays the publication cannot hold. The explain step stores
those rows (compact Parquet beside ``results.json``) and fills the keys by calling the functions
here on the very tables it writes; ``verify`` (``report.recompute.explain``) calls the same
functions on the stored tables. A consistent edit of a published key, or of a stored row, fails.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import pandas as pd

#: Stored file names (``explain/results/``).
MARGINS = "margin_per_gamma.parquet"
DRAWS = "fresh_draws.parquet"
CELLS = "draw_cells.parquet"

#: The margin curve's published columns, by the key suffix they are printed under.
MARGIN_COLUMNS = {"predicted": "mean_predicted", "realized": "mean_realized",
                  "predicted_covered": "mean_predicted_covered", "realized_covered": "mean_realized_covered"}
#: The fresh-draw columns summarized over the fresh draws (``Explain.draws``).
DRAW_COLUMNS = ("share_beyond", "escape_k1", "escape_k8", "failure_k8", "optimism_k8", "paired_fix_k8")


def margin_keys(table: pd.DataFrame) -> dict[str, float]:
    """``margin_per_gamma`` keys of one or more schedules' margin curves (one row per gamma, in the
    search's order, the first at gamma = 1): each gamma's mean predicted and realized failure (all
    episodes, and covered ones only) and the optimism at gamma = 1."""
    out: dict[str, float] = {}
    for label, part in table.groupby("schedule", sort=False):
        if str(label).endswith("_nu_executor"):  # the uncalibrated executor's curve: only its margin is published
            continue
        for row in part.to_dict("records"):
            out.update({f"{label}.g{row['gamma']:.2f}.{key}": float(row[col]) for key, col in MARGIN_COLUMNS.items()})
        first = part.iloc[0]
        out[f"{label}.optimism_at_gamma_1"] = float(first["mean_realized"] - first["mean_predicted"])
        out[f"{label}.optimism_at_gamma_1_covered"] = float(first["mean_realized_covered"] - first["mean_predicted_covered"])
    return out


def draws_keys(table: pd.DataFrame) -> dict[str, float]:
    """``instance_generator.draws.*`` from the fresh-draw rows: the first row is the frozen run redrawn
    (the analytic check), the others fresh draws; per column mean, SD, min and max over the fresh ones."""
    check, fresh = table.iloc[0], table.iloc[1:]
    out: dict[str, float] = {"draws.analytic_B_test_random.escape_k8": float(check["escape_k8"]),
                             "draws.count": int(len(fresh))}
    for col in DRAW_COLUMNS:
        values = fresh[col].to_numpy(float)
        out[f"draws.{col}.mean"] = float(values.mean())
        out[f"draws.{col}.sd"] = float(values.std(ddof=1)) if len(values) > 1 else float("nan")
        out[f"draws.{col}.min"], out[f"draws.{col}.max"] = float(values.min()), float(values.max())
    if len(fresh) > 2:
        out["draws.corr_share_beyond_escape_k8"] = float(np.corrcoef(fresh["share_beyond"], fresh["escape_k8"])[0, 1])
    return out


def cells_table(parts: Mapping[str, Sequence[Mapping[str, float]]], first: Mapping[str, int]) -> pd.DataFrame:
    """The per-draw cells of each part as long rows (``part``, ``draw``, ``cell``, ``value``), cells in the
    order computed; ``first[part]`` numbers the part's first draw (0: the frozen run's check)."""
    rows = [{"part": part, "draw": first[part] + i, "cell": cell, "value": float(v)}
            for part, cells in parts.items() for i, one in enumerate(cells) for cell, v in one.items()]
    return pd.DataFrame(rows, columns=["part", "draw", "cell", "value"]).astype({"draw": "int32"})


def _per_draw(table: pd.DataFrame, part: str, fresh_only: bool) -> list[dict[str, float]]:
    rows = table[(table["part"] == part) & ((table["draw"] > 0) if fresh_only else True)]
    return [dict(zip(p["cell"], p["value"].astype(float))) for _, p in rows.groupby("draw", sort=True)]


def cells_keys(table: pd.DataFrame) -> dict[str, Any]:
    """``instance_generator.draws.{audit,faults}_check`` (draw 0's cells), ``draws.audit`` and
    ``draws.faults`` (the spread over fresh draws), ``draws.audit_fresh_cal`` and
    ``draws.gates_fresh_cal`` (the spread over fresh draw pairs), from the stored cells."""
    from probecommit.studies.explain.draw_audit import spread
    from probecommit.studies.explain.draw_faults import nan_spread

    out: dict[str, Any] = {}
    for part, summarize in (("audit", spread), ("faults", nan_spread)):
        check = table[(table["part"] == part) & (table["draw"] == 0)]
        out.update({f"draws.{part}_check.{c}": float(v) for c, v in zip(check["cell"], check["value"])})
        fresh = _per_draw(table, part, fresh_only=True)
        if fresh:
            out.update({f"draws.{part}.{k}": v for k, v in summarize(fresh).items()})
    for part in ("audit_fresh_cal", "gates_fresh_cal"):
        pairs = _per_draw(table, part, fresh_only=False)
        if pairs:
            out.update({f"draws.{part}.{k}": v for k, v in spread(pairs).items()})
    return out


#: The schedules' stored Probe-Robust rows (``committed_pool``): one ``run`` per trajectory set.
SCHEDULES = "schedule_episodes.parquet"
#: Columns of the cover and random test runs' rows (the gates, the pool labels, the surprise AUC).
TRAJECTORY_COLUMNS = ("instance_id", "repeat", "k", "predicted", "realized", "covered", "escaped", "post_var",
                      "max_surprise", "z_true")
#: Columns of Split A's rows (final budget only: the schedules' failures).
FINAL_COLUMNS = ("instance_id", "repeat", "k", "realized", "escaped")


def schedule_table(runs: Mapping[str, pd.DataFrame], k_cover: int) -> pd.DataFrame:
    """The stored rows of ``committed_pool``: ``ours_B_test``, ``paper_B_test`` (cover schedules) and
    ``random_B_test`` whole (every budget), ``ours_A`` and ``paper_A`` at the cover's final budget.
    ``runs`` holds each run's Probe-Robust episodes (status ok)."""
    parts = []
    for name, rows in runs.items():
        if name.endswith("_A"):
            rows = rows.loc[rows["k"] == k_cover, list(FINAL_COLUMNS)]
        else:
            rows = rows[[c for c in TRAJECTORY_COLUMNS if c in rows]]
        parts.append(rows.assign(run=name))
    return pd.concat(parts, ignore_index=True).astype({"repeat": "int32", "k": "int16"})


def pool_keys(table: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, dict[str, Any]]:
    """``committed_pool`` (each schedule's raw-gate pool under every escape label, both schedules' failures
    at the cover's final budget on Split B test and A, paired) and ``missing``'s surprise AUCs on both cover
    schedules, from the stored rows (``schedule_table``); budgets are the runs' own (1..max k)."""
    from probecommit.audit.stats import cluster_bootstrap_mean, paired_bootstrap
    from probecommit.audit.surprise import surprise_auc
    from probecommit.studies.explain.pool import pool_variants

    run = {name: part.drop(columns="run").reset_index(drop=True) for name, part in table.groupby("run", sort=False)}
    k, kr = int(run["ours_B_test"]["k"].max()), int(run["random_B_test"]["k"].max())
    b = dict(resamples=int(boot["resamples"]), seed=int(boot["seed"]))
    pool: dict[str, Any] = {}
    missing: dict[str, Any] = {}
    for label, name, budgets in (("ours", "ours_B_test", k), ("paper_schedule", "paper_B_test", k),
                                 ("random_schedule", "random_B_test", kr)):
        pool.update({f"{label}.{key}": v for key, v in pool_variants(run[name], list(range(1, budgets + 1)), **b).items()})
    for label, name in (("", "ours_B_test"), ("_paper_schedule", "paper_B_test")):
        auc = surprise_auc(run[name], budgets=[1, k], final_k=k, **b).set_index("k")
        for kk in (1, k):
            missing[f"surprise_auc_cover{label}_k{kk}"] = [float(auc.loc[kk, c]) for c in ("auc", "auc_lo", "auc_hi")]
        missing[f"surprise{label}.n_escaped"] = int(auc.loc[k, "n_escaped"])
        if not label:
            missing["surprise.n_covered"] = int(auc.loc[k, "n_covered"])
    for split in ("B_test", "A"):
        mine, theirs = (run[f"{who}_{split}"][lambda r: r["k"] == k] for who in ("ours", "paper"))
        for label, rows in (("ours", mine), ("paper_schedule", theirs)):
            pool[f"schedule.{split}.{label}.failure_k{k}"] = [float(x) for x in (lambda iv: (iv.estimate, iv.lo, iv.hi))(
                cluster_bootstrap_mean(rows["realized"].to_numpy(float), rows["instance_id"].to_numpy(), **b))]
            pool[f"schedule.{split}.{label}.escape_k{k}"] = float(rows["escaped"].mean())
        d = paired_bootstrap(mine, theirs, "realized", keys=("instance_id", "repeat"), **b).difference
        pool[f"schedule.{split}.paper_minus_ours_failure_k{k}"] = [float(d.estimate), float(d.lo), float(d.hi)]
    return {"committed_pool": pool, "missing": missing}


def _probe(rows: pd.DataFrame, k: int | None = None) -> pd.DataFrame:
    rows = rows[(rows["method"] == "probe_robust") & (rows["status"] == "ok")]
    return rows if k is None else rows[rows["k"] == k]


def harness_keys(faults: pd.DataFrame, runs: Mapping[str, pd.DataFrame], schedules: pd.DataFrame, *, k_cover: int,
                 k_random: int, edge: float, expected: float, boot: Mapping[str, int]) -> dict[str, dict[str, Any]]:
    """``boundary_fault`` (the fault harness's boundary arm by stratum, its fix, Test C's escape and fix),
    ``missing``'s whole-cluster escapes and Test C's final escapes, and ``instance_generator.stratified``,
    from the insertion study's stored fault episodes and run episodes (``runs``: by run name) and the
    stored cover test rows (``schedules``). ``expected`` is the generator's share beyond ``edge``."""
    from probecommit.audit.stats import cluster_bootstrap_mean, paired_bootstrap
    from probecommit.studies.explain.generator import stratified_metrics

    b = dict(resamples=int(boot["resamples"]), seed=int(boot["seed"]))
    triple = lambda iv: [float(iv.estimate), float(iv.lo), float(iv.hi)]  # noqa: E731
    out: dict[str, Any] = {}
    fault = faults[(faults["fault"] == "boundary") & (faults["arm"] == "fault")]
    fix = faults[(faults["fault"] == "boundary") & (faults["arm"] == "fix")]
    for k in (1, k_random):
        s = stratified_metrics(fault, k, edge, expected)
        out.update({f"harness.k{k}.{key}": v for key, v in s.items() if key.startswith(("escape", "share", "optimism", "failure"))})
    f8, x8 = _probe(fault, k_random), _probe(fix, k_random)
    out["harness.paired_fix"] = triple(paired_bootstrap(f8, x8, "realized", **b).difference)
    beyond = np.abs(f8.set_index(["instance_id", "repeat"])["z_true"]) > edge
    diff = (x8.set_index(["instance_id", "repeat"])["realized"] - f8.set_index(["instance_id", "repeat"])["realized"])
    inside_fix, beyond_fix = float(diff[~beyond].mean()), float(diff[beyond].mean())
    out["harness.paired_fix.inside"], out["harness.paired_fix.beyond"] = inside_fix, beyond_fix
    out["harness.paired_fix.standardized"] = (1 - expected) * inside_fix + expected * beyond_fix
    old, new = runs["C_random"], runs["C_random_corrected"]
    for k in (1, k_random):
        out[f"testc.k{k}.escape"] = triple(cluster_bootstrap_mean(
            _probe(old, k)["escaped"].to_numpy(float), _probe(old, k)["instance_id"].to_numpy(), **b))
    out["testc.paired_fix"] = triple(paired_bootstrap(_probe(old, k_random), _probe(new, k_random), "realized", **b).difference)
    missing: dict[str, Any] = {}
    for name, k in (("C_cover_corrected", k_cover), ("C_random_corrected", k_random), ("C_cover", k_cover),
                    ("C_random", k_random)):
        missing[f"testc_final_escapes.{name}"] = int(_probe(runs[name], k)["escaped"].sum())
    for name in ("prior", "boundary"):
        rows = _probe(faults[(faults["fault"] == name) & (faults["arm"] == "fault")])
        for k in (1, k_random):
            at = rows[rows["k"] == k].groupby("instance_id")["escaped"].agg(["sum", "count"])
            any_ = at["sum"] > 0
            missing[f"all_repeats_escape.{name}.k{k}.escape"] = float(rows[rows["k"] == k]["escaped"].mean())
            missing[f"all_repeats_escape.{name}.k{k}.clusters_all"] = float((at["sum"] == at["count"]).mean())
            missing[f"all_repeats_escape.{name}.k{k}.of_escaping_clusters"] = float(
                (at["sum"] == at["count"])[any_].mean()) if any_.any() else float("nan")
    cover = schedules[schedules["run"] == "ours_B_test"].drop(columns="run").assign(method="probe_robust", status="ok")
    strata: dict[str, Any] = {}
    for name, rows, k in (("B_test_random", runs["B_test_random"], k_random), ("C_random", runs["C_random"], k_random),
                          ("B_test_cover", cover, k_cover), ("C_cover", runs["C_cover"], k_cover)):
        strata.update({f"stratified.{name}.k{k}.{key}": v for key, v in stratified_metrics(rows, k, edge, expected).items()})
    return {"boundary_fault": out, "missing": missing, "instance_generator": strata}


def physx_coverage_keys(episodes: pd.DataFrame, k: int) -> dict[str, float]:
    """``missing.physx_{cluster,episode}_coverage.<variant>`` at budget ``k`` from the SAPIEN B_test_random runs'
    episodes (a ``variant`` column: the run directories' in the explain step, the engines study's stored
    ``engine_episodes.parquet`` in verify)."""
    out: dict[str, float] = {}
    for variant, part in episodes.groupby("variant", sort=False):
        rows = _probe(part, k)
        out[f"physx_cluster_coverage.{variant}"] = float(rows.groupby("instance_id")["covered"].all().mean())
        out[f"physx_episode_coverage.{variant}"] = float(rows["covered"].mean())
    return out


def fill_group(job: Any, group: str, name: str, run: Callable[[Path, bool], tuple[dict[str, Any], pd.DataFrame]]) -> None:
    """A stored-row step's keys into ``job.res[group]`` and its rows beside ``results.json`` as ``name`` (none when
    the step found no run): ``run(root, quick) -> (keys, rows)``, so ``verify`` recomputes the keys from the rows."""
    keys, rows = run(Path(job.root), bool(job.quick))
    job.res[group].update(keys)
    if len(rows):
        job.stored[name] = rows


def recompute_group(folder: Path, results: Mapping[str, Any], group: str, stored: str,
                    recompute: Callable[[Path, dict[str, Any]], Mapping[str, Any]]) -> tuple[dict[str, Any],
                                                                                         dict[str, str], list[str]]:
    """One result group's keys recomputed from its stored rows (``verify``), the contract of
    ``report.recompute.SELF_RECOMPUTING``: ``(values, sources, problems)`` keyed as ``explain:results``;
    a group published without its stored rows (``stored``) is a problem. ``recompute(folder, published)``
    is the group's own summary of the rows, called with the group's published keys."""
    values = {f"{group}.{k}": v for k, v in recompute(folder, results.get(group, {})).items()}
    problems = ([f"explain/{stored}: missing (the rows {group}'s keys are recomputed from)"]
                if results.get(group) and not (folder / stored).is_file() else [])
    return values, dict.fromkeys(values, stored), problems


def recompute_bootstrapped(folder: Path, results: Mapping[str, Any], group: str, name: str,
                           summary: Callable[[pd.DataFrame], Mapping[str, Any]]) -> dict[str, tuple[Any, str]]:
    """One bootstrapped group's keys from its stored rows ``name`` (``verify``, the contract of
    ``report.recompute.BOOTSTRAPPED``): ``{"<group>.<key>": (value, name)}``; none when the rows are not there or
    the group was not published. ``summary(rows)`` is the group's own keys function, with the bootstrap settings
    bound by the caller."""
    if not (Path(folder) / name).is_file() or not results.get(group):
        return {}
    return {f"{group}.{key}": (v, name) for key, v in summary(pd.read_parquet(Path(folder) / name)).items()}


def recompute_stored(folder: Path, published: Mapping[str, Any], name: str,
                     keys: Callable[[pd.DataFrame], dict[str, Any]]) -> dict[str, Any]:
    """A step's keys again from its stored rows ``name`` (``verify``); none when the rows are not there or the
    publication holds none of the step's keys."""
    if not (Path(folder) / name).is_file() or not published:
        return {}
    return keys(pd.read_parquet(Path(folder) / name))


def over_families(root: Path, quick: bool, families: Sequence[str], family_rows: Callable[..., pd.DataFrame],
                  keys: Callable[[pd.DataFrame], dict[str, Any]],
                  files: Sequence[str] = ("episodes.parquet",)) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and stored rows of a step run per Table II family on the breadth runs under ``root``
    (``family_rows(root, family, quick)``); a family whose run lacks one of ``files`` is left out."""
    from probecommit.studies.explain.ex8_blind import run_dir

    present = [f for f in families if all((run_dir(root, f, quick) / name).is_file() for name in files)]
    if not present:
        return {}, pd.DataFrame()
    rows = pd.concat([family_rows(root, f, quick) for f in present], ignore_index=True)
    return keys(rows), rows
