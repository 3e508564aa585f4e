"""Recompute a publication's summary numbers from its stored episode-level tables.

Why: a manifest re-hashed after an edit proves nothing; a number is trusted only when the
same code that made it, run again on the lowest stored tables with the stored seeds, gives
it again. Each study has one function ``<study>(folder, results) -> Recomputed``: the values
it recomputes, keyed like ``results.json`` (``"table_testc.escape_random_k8.old"``), and the
derived Parquet tables it rebuilds (``"fault_signatures.parquet"``). ``verify`` compares.

What is recomputed and what is not is listed in ``RECOMPUTED`` and ``TRACED_ONLY``
(``docs/verify.md`` prints them). Numbers that need beliefs recomputed from stored probes
(calibrated commits, margins, gates, replays under robust filters or faults) are recomputed
from the re-executed rows publishing stores beside them (``commits.parquet`` and friends).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import pandas as pd


@dataclass
class Recomputed:
    """Values by results.json key, and rebuilt derived tables by file name."""

    values: dict[str, Any] = field(default_factory=dict)
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    #: The stored table each value was recomputed from, by the key's first part (for messages).
    sources: dict[str, str] = field(default_factory=dict)

    #: The stored table each rebuilt table was derived from (for messages).
    table_sources: dict[str, str] = field(default_factory=dict)
    #: Stored columns that follow from lower stored tables: (ok, message naming the file and the number).
    consistency: list[tuple[bool, str]] = field(default_factory=list)

    def source(self, key: str) -> str:
        """The stored table a key was recomputed from: the longest source prefix of the key names it."""
        parts = key.split(".")
        for n in range(len(parts), 0, -1):
            if ".".join(parts[:n]) in self.sources:
                return self.sources[".".join(parts[:n])]
        return "the stored episode tables"


def _triple(iv: Any) -> list[float]:
    return [float(iv.estimate), float(iv.lo), float(iv.hi)]


# ----------------------------------------------------------------------------- insertion


def insertion(folder: Path, results: dict[str, Any]) -> Recomputed:
    """Tables IV (Split A), III (uncalibrated half, thresholds), VI, VII, the text's escapes, scan,
    cover search, re-splits and the fault signatures, from ``episodes.parquet`` and friends."""
    from probecommit.audit.conformal import budget_thresholds, instance_scores
    from probecommit.audit.stats import cluster_bootstrap_mean, paired_bootstrap
    from probecommit.studies.insertion import episode_metrics, paired

    setup = results["setup"]
    boot = dict(resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))
    out = Recomputed()
    v = out.values
    ep = pd.read_parquet(folder / "episodes.parquet")
    runs = {name: part.drop(columns="run").reset_index(drop=True) for name, part in ep.groupby("run", sort=False)}

    a = runs["A_cover"]
    blind = a[(a.method == "blind_bayes") & (a.status == "ok")]
    v["table_insertion.A.no_probe"] = _triple(cluster_bootstrap_mean(
        blind["realized"].to_numpy(float), blind["instance_id"].to_numpy(), **boot))
    v["table_insertion.A.cover_k5"] = episode_metrics(a, 5, **boot)["failure"]
    cover = a[(a.method == "probe_robust") & (a.k == 5) & (a.status == "ok")]
    v["table_insertion.A.paired_reduction_k5"] = _triple(
        paired_bootstrap(cover, blind, "realized", keys=("instance_id", "repeat"), **boot).difference)

    alpha = float(setup["alpha"])
    for name, budgets in (("B_cal_cover", [1, 2, 3, 4, 5]), ("B_cal_random", [1, 2, 3, 5, 8])):
        if name in runs:
            probe = runs[name][(runs[name].method == "probe_robust") & (runs[name].status == "ok")]
            t_k = budget_thresholds(instance_scores(probe), alpha, budgets)
            kind = name.split("_")[-1]
            v[f"table_insertion.thresholds_{kind}"] = {str(k): float(t) for k, t in t_k.items()}

    test = runs["B_test_random"]
    if (folder / COMMITS).is_file():  # a missing stored table is a failure of its own (``STORED_TABLES``)
        _calibrated(folder, runs, results, boot, out)
    for k in (1, 8):
        m = episode_metrics(test, k, **boot)
        v[f"text.escape_k{k}"], v[f"text.episode_coverage_k{k}"] = m["escape"], m["episode_coverage"]

    spec = [("escape_random_k8", "C_random", 8, "escaped", "escape"),
            ("episode_coverage_random_k8", "C_random", 8, "covered", "episode_coverage"),
            ("optimism_random_k8", "C_random", 8, "optimism", "optimism"),
            ("failure_random_k8", "C_random", 8, "realized", "failure"),
            ("failure_cover_k5", "C_cover", 5, "realized", "failure"),
            ("failure_cover_k1", "C_cover", 1, "realized", "failure")]
    for key, run, k, col, name in spec:
        old, new = runs[run], runs[f"{run}_corrected"]
        v[f"table_testc.{key}.old"] = episode_metrics(old, k, **boot)[name]
        v[f"table_testc.{key}.corrected"] = episode_metrics(new, k, **boot)[name]
        v[f"table_testc.{key}.old_minus_corrected"] = paired(new, old, k, col, **boot)

    _faults(folder, setup, boot, out)
    _small_tables(folder, out)
    if (folder / "robust_episodes.parquet").is_file():
        _robust(folder, setup, boot, out)
    out.sources = {"table_insertion": "episodes.parquet", "table_audit": "episodes.parquet", "text": "episodes.parquet", "table_testc": "episodes.parquet",
                   "table_faults": "faults_episodes.parquet", "fault_signatures": "faults_episodes.parquet", "scan": "scan.parquet", "cover": "cover_search.parquet",
                   "resplits": "resplits.parquet", "gates": COMMITS, "robust": "robust_episodes.parquet", "coverage": "episodes.parquet"}
    for key in ("table_insertion.B", "table_insertion.margin_cover", "table_insertion.margin_random",
                "table_insertion.distribution_free_margin_cover", "table_insertion.simultaneous_cover",
                "table_insertion.simultaneous_random", "table_audit", "table_testc.failure_cover_k5_setcal_margin"):
        out.sources[key] = f"{COMMITS} and episodes.parquet"
    return out


#: The calibrations' re-executed rows (``studies.insertion.store_commits``).
COMMITS = "commits.parquet"
#: Budgets each stored calibration calibrates (``studies.insertion.InsertionReproduction``).
CALIBRATION_BUDGETS = {"cover": [1, 2, 3, 4, 5], "random": [1, 2, 3, 5, 8], "testc_old": [1, 2, 3, 4, 5],
                       "testc_corrected": [1, 2, 3, 4, 5]}


def _calibrated(folder: Path, runs: dict[str, pd.DataFrame], results: dict[str, Any], boot: dict[str, int],
                out: Recomputed) -> None:
    """Table IV Split B, Table III (both halves), the margins, Test C's set + margin row and the commit
    gates, from the stored re-executed commits and the runs' stored episodes (``runner.calibration``'s
    ``calibration_from_tables`` and ``gates_from_commits``: the functions ``calibrate`` and ``gates`` end in)."""
    from probecommit.studies.insertion import CALIBRATIONS, setmargin_failure, setmargin_paired
    from probecommit.runner.calibration import calibration_from_tables

    commits = pd.read_parquet(folder / COMMITS)
    alpha = float(results["setup"]["alpha"])
    by_name = {name: part.reset_index(drop=True) for name, part in commits.groupby("calibration", sort=False)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a margin search that settles on the grid's end (quick runs)
        cal = {name: calibration_from_tables(by_name[name], runs[CALIBRATIONS[name][0]], runs[CALIBRATIONS[name][1]],
                                             alpha, budgets, **boot)
               for name, budgets in CALIBRATION_BUDGETS.items()}
    v = out.values
    v["table_insertion.B.cost_table"] = cal["cover"].cost.to_dict("records")
    v["table_insertion.B.cost_differences"] = cal["cover"].cost_differences.to_dict("records")
    v["table_insertion.distribution_free_margin_cover"] = float(cal["cover"].distribution_free_margin)
    for name in ("cover", "random"):
        v[f"table_insertion.margin_{name}"] = cal[name].margin.gamma
        v[f"table_insertion.simultaneous_{name}"] = float(cal[name].simultaneous_threshold)
    v["table_audit.table"] = cal["random"].table3.to_dict("records")
    v["table_audit.summary"] = cal["random"].summary
    setmargin = {name: setmargin_failure(cal[f"testc_{name}"]) for name in ("old", "corrected")}
    v["table_testc.failure_cover_k5_setcal_margin"] = {
        **setmargin, "old_minus_corrected": setmargin_paired(cal["testc_old"], cal["testc_corrected"], **boot),
        "simultaneous_threshold": {n: float(cal[f"testc_{n}"].simultaneous_threshold) for n in setmargin}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _gates(by_name["gates"], runs, results, alpha, boot, out)


def _gates(commits: pd.DataFrame, runs: dict[str, pd.DataFrame], results: dict[str, Any], alpha: float,
           boot: dict[str, int], out: Recomputed) -> None:
    """The commit gates (summary, curves, t and gamma) and Fig. 6's coverage panel, from stored rows; and the
    stored uncalibrated gate rows against the test run's stored episodes (they are the same commits)."""
    from probecommit.studies.insertion import CALIBRATIONS
    from probecommit.studies.insertion import coverage_vs_nominal
    from probecommit.runner.calibration import gates_from_commits

    cal_run, test_run = CALIBRATIONS["gates"]
    raw = commits.loc[commits["request"] == "raw"]
    budgets = sorted(int(k) for k in raw["k"].unique())
    result = gates_from_commits(commits, runs[cal_run], alpha, budgets, **boot)
    out.values["gates.summary"] = result.summary.to_dict("records")
    out.values.update({f"gates.info.{key}": result.info[key] for key in ("threshold", "gamma", "gamma_satisfied", "alpha")})
    out.values["gates.info.surprise"] = result.info["surprise"].to_dict("records")
    out.tables["gates_curves.parquet"] = result.curves
    out.table_sources["gates_curves.parquet"] = COMMITS
    k = int(results["setup"]["k_random"])
    out.tables["coverage_vs_nominal.parquet"] = coverage_vs_nominal(runs["B_cal_random"], runs["B_test_random"], k)
    out.table_sources["coverage_vs_nominal.parquet"] = "episodes.parquet (B_cal_random, B_test_random)"
    stored = runs[test_run]
    stored = stored[(stored["method"] == "probe_robust") & stored["k"].isin(budgets)]
    keys = ["instance_id", "repeat", "k"]
    both = raw.astype({"repeat": "int64"}).merge(stored, on=keys, how="outer", suffixes=("", "_stored"), indicator=True)
    unmatched = both[both["_merge"] != "both"]
    out.consistency.append((unmatched.empty, f"insertion/{COMMITS}: gates raw rows and episodes.parquet {test_run} differ "
                                             f"in their episodes ({len(unmatched)} unmatched, e.g. "
                                             f"{unmatched[keys].head(1).to_dict('records')})"))
    for column in ("predicted", "realized", "escaped", "status"):
        a, b = both[column].to_numpy(), both[f"{column}_stored"].to_numpy()
        same = [x == y or (x != x and y != y) for x, y in zip(a, b)]
        bad = [i for i, ok in enumerate(same) if not ok]
        row = both.iloc[bad[0]] if bad else None
        out.consistency.append((not bad, f"insertion/{COMMITS}: gates raw {column} = "
                                         f"{None if row is None else row[column]} at {None if row is None else row[keys].to_dict()}"
                                         f" but episodes.parquet {test_run} holds {None if row is None else row[column + '_stored']}"))


def _faults(folder: Path, setup: dict[str, Any], boot: dict[str, int], out: Recomputed) -> None:
    from probecommit.audit.surprise import surprise_auc
    from probecommit.studies.insertion import episode_metrics, paired, probe_rows, signature_points
    from probecommit.studies.faults import FAULTS, signature_table

    episodes = pd.read_parquet(folder / "faults_episodes.parquet")
    kmax = int(setup["k_random"])
    for fault in FAULTS:
        fa = episodes[(episodes.fault == fault) & (episodes.arm == "fault")]
        if not len(fa):
            continue
        out.values[f"table_faults.{fault}.fail"] = episode_metrics(fa, kmax, **boot)["failure"]
        probe = probe_rows(fa)
        if probe[probe.k == kmax]["escaped"].any():
            auc = surprise_auc(probe, final_k=kmax, **boot)
            out.values[f"table_faults.{fault}.surprise_auc"] = float(auc[auc.k == kmax]["auc"].iloc[0])
        for arm in ("tempered", "fix"):
            other = episodes[(episodes.fault == fault) & (episodes.arm == arm)]
            if len(other):
                out.values[f"table_faults.{fault}.{arm}"] = episode_metrics(other, kmax, **boot)["failure"]
        fix = episodes[(episodes.fault == fault) & (episodes.arm == "fix")]
        if len(fix):
            out.values[f"table_faults.{fault}.paired_fix"] = paired(fa, fix, kmax, "realized", **boot)
    signatures = signature_table(episodes)
    out.tables["fault_signatures.parquet"] = signatures
    out.table_sources["fault_signatures.parquet"] = "faults_episodes.parquet"
    out.values["fault_signatures"] = signature_points(signatures)


def _robust(folder: Path, setup: dict[str, Any], boot: dict[str, int], out: Recomputed) -> None:
    """The robust filters: the tuning table tuned again from each candidate's stored final-budget rows on the
    development run, and every arm's metrics and paired difference from its stored rows (``robust_summary``)."""
    from probecommit.studies.insertion import robust_summary
    from probecommit.studies.robust import final_failure, mark_chosen

    rows = pd.read_parquet(folder / "robust_episodes.parquet")
    tuning = rows[rows["part"] == "tuning"]
    table = pd.DataFrame([{"family": family, "value": float(value), "failure": final_failure(part)}
                          for (family, value), part in tuning.groupby(["family", "value"], sort=False)])
    arms = {name: part.reset_index(drop=True) for name, part in rows[rows["part"] != "tuning"].groupby("part", sort=False)}
    out.values["robust"] = robust_summary(mark_chosen(table), arms, int(setup["k_random"]), boot)


def _small_tables(folder: Path, out: Recomputed) -> None:
    """Scan, cover search and re-split summaries from their stored per-scan / per-split tables."""
    off = pd.read_parquet(folder / "scan.parquet")["offset"]
    out.values.update({"scan.delta": float(off.mean()), "scan.sd": float(off.std(ddof=1)) if len(off) > 1 else 0.0,
                       "scan.min": float(off.min()), "scan.max": float(off.max()), "scan.scans": int(len(off)),
                       "scan.shift_vs_deployed_mm": float(off.mean() + 1.2)})
    cover = pd.read_parquet(folder / "cover_search.parquet")
    out.values.update({"cover.winner": [float(u) for u in json.loads(str(cover["schedule"].iloc[0]))],
                       "cover.winner_failure": float(cover["failure"].iloc[0]), "cover.candidates": int(len(cover))})
    table = pd.read_parquet(folder / "resplits.parquet")
    out.values.update({
        "resplits.level_mean_sd": [float(table.level.mean()), float(table.level.std(ddof=1))],
        "resplits.failure_mean_sd": [float(table.failure.mean()), float(table.failure.std(ddof=1))],
        "resplits.heldout_cluster_coverage": float(table.heldout_cluster_coverage.mean()),
        "resplits.margin_optimistic_fraction": float(table.margin_optimistic.mean()),
        "resplits.splits": int(len(table))})


# ----------------------------------------------------------------------------- breadth and cost


def breadth(folder: Path, results: dict[str, Any]) -> Recomputed:
    """Table II's rows (but insertion's, checked against the insertion study) and the budget curves."""
    from probecommit.studies.breadth import SUCCESS_FAMILIES, as_success, breadth_table, budget_curves

    settings = results["settings"]
    ep = pd.read_parquet(folder / "breadth_episodes.parquet")
    runs = {f: part.drop(columns="family").reset_index(drop=True) for f, part in ep.groupby("family", sort=False)}
    boot = dict(resamples=int(settings["resamples"]), seed=int(settings["seed"]))
    table = breadth_table(runs, int(settings["k"]), **boot)
    rows = [as_success(r) if r["family"] in SUCCESS_FAMILIES else r for r in table.to_dict("records")]
    out = Recomputed()
    stored = pd.read_parquet(folder / "table_II_breadth.parquet")
    insertion_rows = stored[stored["family"] == "insertion_A"]
    out.tables["table_II_breadth.parquet"] = pd.concat([insertion_rows, pd.DataFrame(rows)], ignore_index=True)
    out.tables["budget_curves.parquet"] = budget_curves(runs)
    out.table_sources = {"table_II_breadth.parquet": "breadth_episodes.parquet",
                         "budget_curves.parquet": "breadth_episodes.parquet"}
    if (folder / SIGN_FLIP_ROWS).is_file():  # each success family's per-truth sign count (``sign_flip_summary``)
        from probecommit.studies.breadth import FAMILY_K, sign_flip_summary

        for family, part in pd.read_parquet(folder / SIGN_FLIP_ROWS).groupby("family", sort=False):
            out.values[f"sign_flip_over_truths.{family}"] = sign_flip_summary(part.drop(columns="family"), FAMILY_K[family])
        out.sources["sign_flip_over_truths"] = SIGN_FLIP_ROWS
    elif results.get("sign_flip_over_truths"):  # published sign counts need their stored rows
        out.consistency.append((False, f"breadth/{SIGN_FLIP_ROWS}: missing (the rows sign_flip_over_truths.* are "
                                       "recomputed from)"))
    return out


#: Success families' episodes with each instance's feasibility and truth (``studies.breadth.SIGN_FLIP_ROWS``).
SIGN_FLIP_ROWS = "sign_flip_rows.parquet"


def cost(folder: Path, results: dict[str, Any]) -> Recomputed:
    """The break-even prices from the breadth curves the cost study stores beside them."""
    from probecommit.studies.breadth import SUCCESS_FAMILIES
    from probecommit.studies.pricing import pricing_table

    curves = pd.read_parquet(folder.parent / "breadth" / "budget_curves.parquet")
    out = Recomputed()
    out.tables["pricing.parquet"] = pricing_table(curves[~curves["family"].isin(SUCCESS_FAMILIES)])
    out.table_sources["pricing.parquet"] = "breadth/budget_curves.parquet"
    return out


def engines(folder: Path, results: dict[str, Any]) -> Recomputed:
    """Table VI, the paired failure differences and escape against k, from the stored engine episodes."""
    from probecommit.studies.engines import summarize_engine_runs

    settings = results["settings"]
    episodes = pd.read_parquet(folder / "engine_episodes.parquet")
    table, paired_rows, escape = summarize_engine_runs(episodes, resamples=int(settings["resamples"]),
                                                       seed=int(settings["seed"]))
    flat = table.copy()
    flat.columns = [f"{e}/{v}" for e, v in flat.columns]
    out = Recomputed(tables={"table_VI_engines.parquet": flat, "escape_by_budget.parquet": escape})
    out.values["paired_failure"] = paired_rows
    out.values["paired"] = {f"{p['engine']}/{p['variant']}": p["failure_difference"] for p in paired_rows}
    out.values["escape"] = {f"{e}/{v}": {str(int(r["k"])): float(r["escape"]) for _, r in part.iterrows()}
                            for (e, v), part in escape.groupby(["engine", "variant"], sort=False)}
    out.values["table"] = {f"{e}/{v}": dict(zip([r.replace(" ", "_") for r in table.index], map(float, table[(e, v)])))
                           for e, v in table.columns}
    out.sources = dict.fromkeys(out.values, "engine_episodes.parquet")
    if (folder / "engine_scans.parquet").is_file():
        from probecommit.studies.engines import scan_summaries

        for engine, summary in scan_summaries(pd.read_parquet(folder / "engine_scans.parquet")).items():
            for kind, values in summary.items():
                out.values[f"scans.{engine}.{kind}"] = values
        out.sources["scans"] = "engine_scans.parquet"
    out.table_sources = {"table_VI_engines.parquet": "engine_episodes.parquet",
                         "escape_by_budget.parquet": "engine_episodes.parquet"}
    return out


def robot(folder: Path, results: dict[str, Any]) -> Recomputed:
    """Table VII and the session's counts from the stored session episodes; the sweep summaries from the
    stored sweeps (the sweeps themselves are replays: traced only)."""
    from probecommit.robot.table import robot_table
    from probecommit.studies.robot import boundary_holds_to

    rows = pd.read_parquet(folder / "robot_episodes.parquet")
    out = Recomputed(tables={"table_robot.parquet": robot_table(rows)})
    out.values.update({"episodes": int(len(rows)), "positions": int(rows["instance_id"].nunique()),
                       "n_covered": int(rows["covered"].sum()), "n_escaped": int(rows["escaped"].sum()),
                       "optimism_pooled": float((rows["realized"] - rows["predicted"]).mean())})
    out.sources = dict.fromkeys(out.values, "robot_episodes.parquet")
    boundary = pd.read_parquet(folder / "fault_boundary.parquet")
    out.values["boundary_holds_to_mm"] = boundary_holds_to(boundary)
    out.sources["boundary_holds_to_mm"] = "fault_boundary.parquet"
    out.table_sources = {"table_robot.parquet": "robot_episodes.parquet"}
    if (folder / SWEEPS).is_file():
        _sweeps(folder, results, rows, out)
    return out


#: The robot fault sweeps' replay rows (``robot.replay.fault_sweep``'s record).
SWEEPS = "fault_sweep_episodes.parquet"


def _sweeps(folder: Path, results: dict[str, Any], session: pd.DataFrame, out: Recomputed) -> None:
    """Both fault sweeps computed again from their stored replay rows (``robot.replay.sweep_rows``), the first
    resolved boundary size from them; and the deployed replay's rows against the session's stored episodes
    (the session reproduces under replay: ``replay_reproduced_fraction`` 1)."""
    from probecommit.audit.stats import DEFAULT_RESAMPLES, DEFAULT_SEED
    from probecommit.robot.replay import sweep_rows

    stored = pd.read_parquet(folder / SWEEPS)
    _prior_by_position(stored, session, results, out)
    resamples = int(results.get("sweep_resamples", DEFAULT_RESAMPLES))
    for fault in ("boundary", "prior"):
        table = sweep_rows(stored[stored["fault"] == fault], resamples=resamples, seed=DEFAULT_SEED)
        out.tables[f"fault_{fault}.parquet"] = table
        out.table_sources[f"fault_{fault}.parquet"] = SWEEPS
        if fault == "boundary":
            resolved = table[table["optimism_resolved"] & (table["size"] > 0)]
            out.values["boundary_first_resolved_mm"] = float(resolved["size"].min()) if len(resolved) else None
            out.sources["boundary_first_resolved_mm"] = SWEEPS
    if results.get("replay_reproduced_fraction") != 1.0:
        return
    for fault, part in stored[stored["size"].isna()].groupby("fault", sort=False):
        joined = part.merge(session, on="episode", suffixes=("", "_session"))
        for column in ("predicted", "realized", "covered", "escaped"):
            bad = joined[joined[column].astype(float) != joined[f"{column}_session"].astype(float)]
            first = bad.iloc[0] if len(bad) else None
            out.consistency.append((bad.empty and len(joined) == len(session) == len(part),
                                    f"robot/{SWEEPS}: the deployed replay ({fault} sweep) has {len(part)} rows, "
                                    f"{len(joined)} matching robot_episodes.parquet's {len(session)}" if first is None else
                                    f"robot/{SWEEPS}: the deployed replay ({fault} sweep) episode {first['episode']} "
                                    f"{column} = {first[column]} but robot_episodes.parquet holds {first[column + '_session']}"))


def _prior_by_position(stored: pd.DataFrame, session: pd.DataFrame, results: dict[str, Any], out: Recomputed) -> None:
    """E222's split of the narrowed prior's replay by block position, from the stored sweep rows and the session's
    episodes (the share it mixes at is the paper's, read from the published record)."""
    from probecommit.studies.robot import prior_by_position

    for size, rec in (results.get("prior_by_position") or {}).items():
        got = prior_by_position(stored, session, float(size), share=rec.get("share"))
        out.values.update({f"prior_by_position.{size}.{k}": v for k, v in got.items()})
        out.sources.update(dict.fromkeys((f"prior_by_position.{size}.{k}" for k in got), SWEEPS))


def gru(folder: Path, results: dict[str, Any]) -> Recomputed:
    """The GRU table from the per-episode misses of the pipeline and of each GRU seed (``studies.gru``);
    the bootstrap settings are the stored ones (the frozen config's for a publication that predates them)."""
    from probecommit.studies.gru import load_gru_config, summarize_gru

    cfg = load_gru_config()
    bootstrap = results.get("bootstrap") or cfg["bootstrap"]
    per_episode = pd.read_parquet(folder / "gru_episodes.parquet")
    summary = summarize_gru(per_episode, bootstrap, float(results.get("equivalence_margin", cfg["equivalence_margin"])))
    summary.pop("equivalence_margin")  # a setting, not a result
    out = Recomputed(values=summary)
    out.sources = dict.fromkeys(summary, "gru_episodes.parquet")
    return out


def beyond(folder: Path, results: dict[str, Any]) -> Recomputed:
    """Beyond's three tables from ``beyond_episodes.parquet``: the plateau comparison recalibrated from its
    recorded commits and the insertion study's stored B_cal_random / B_test_random episodes, the moves from
    their replays' rows, the adaptive comparison from each run's and schedule's rows."""
    from probecommit.audit.conformal import DEFAULT_ALPHA
    from probecommit.runner.calibration import calibration_from_tables
    from probecommit.studies.beyond import EPISODES_FILE, PLATEAU_RESAMPLES, adaptive_table, move_table, plateau_rows

    out = Recomputed()
    if not (folder / EPISODES_FILE).is_file():
        return out
    rows = pd.read_parquet(folder / EPISODES_FILE)
    part = lambda name: rows[rows["part"] == name].reset_index(drop=True)  # noqa: E731
    out.tables["moves.parquet"] = move_table(part("moves"))
    out.tables["adaptive.parquet"] = adaptive_table(part("adaptive"))
    ep = pd.read_parquet(folder.parent / "insertion" / "episodes.parquet")
    runs = {name: p.drop(columns="run").reset_index(drop=True) for name, p in ep.groupby("run", sort=False)}
    resamples = int(results.get("settings", {}).get("plateau_resamples", PLATEAU_RESAMPLES))
    tables = []
    for mode, commits in part("plateau").groupby("plateau", sort=False):
        budgets = sorted(int(k) for k in commits.loc[commits["request"] == "set_margin", "k"].unique())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a margin search that settles on the grid's end
            result = calibration_from_tables(commits.reset_index(drop=True), runs["B_cal_random"], runs["B_test_random"],
                                             DEFAULT_ALPHA, budgets, resamples=resamples)
        tables.append(plateau_rows(result, mode))
    out.tables["plateau.parquet"] = pd.concat(tables, ignore_index=True)
    out.table_sources = {"moves.parquet": EPISODES_FILE, "adaptive.parquet": EPISODES_FILE,
                         "plateau.parquet": f"{EPISODES_FILE} and insertion/episodes.parquet"}
    return out


# ----------------------------------------------------------------------------- explain


def explain(folder: Path, results: dict[str, Any]) -> Recomputed:
    """The explain keys, each from the stored rows it summarizes through the function the explain step fills it
    with (``studies.explain.stored``, ``calibration_rows``, ``robust_rows`` and each step's key function; the
    list is ``RECOMPUTED["explain"]``): every explain key but a retrained seed's parameters and the paper's values."""
    from probecommit.studies.explain import stored

    out = Recomputed()
    for group, name, summarize in (("margin_per_gamma", stored.MARGINS, stored.margin_keys),
                                   ("instance_generator", stored.DRAWS, stored.draws_keys),
                                   ("instance_generator", stored.CELLS, stored.cells_keys)):
        if not (folder / name).is_file():  # a missing stored table is a failure of its own (``STORED_TABLES``)
            continue
        for key, value in summarize(pd.read_parquet(folder / name)).items():
            out.values[f"{group}.{key}"] = value
            out.sources[f"{group}.{key}"] = name
    if (folder / stored.SCHEDULES).is_file():
        _schedules(folder, results, out)
    _calibration_rows(folder, out)
    _scan_copies(folder, results, out)
    _gru_copies(folder, results, out)
    _replays(folder, out)
    _searches(folder, out)
    _generator(folder, out)
    if (folder / EXPLAIN_BREADTH).is_file():
        _breadth_prior(folder, results, out)
    _cost_copies(folder, out)
    engines = folder.parent / "engines" / "engine_episodes.parquet"
    if engines.is_file():
        _engine_keys(folder, results, pd.read_parquet(engines), out)
    if (folder / EXPLAIN_RIG[0]).is_file() and (folder / EXPLAIN_RIG[1]).is_file():
        from probecommit.studies.explain import rig

        setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]["bootstrap"]
        boot = dict(resamples=int(setup["resamples"]), seed=int(setup["seed"]))
        variants = {group: pd.read_parquet(folder / name) for group, name in rig.VARIANTS.items()
                    if (folder / name).is_file()}
        for key, value in rig.keys(*(pd.read_parquet(folder / name) for name in EXPLAIN_RIG), boot, variants).items():
            out.values[f"rig_redraws.{key}"] = value
        out.sources["rig_redraws"] = " and ".join(EXPLAIN_RIG)
    _stored_summaries(folder, results, out)
    _ex4_cone(folder, results, out)
    if "ex4_pricing" in results:  # a pure function of the paper's printed values (studies.explain.ex4_pricing)
        from probecommit.studies.explain.ex4_pricing import keys as ex4_pricing_keys

        out.values.update({f"ex4_pricing.{key}": value for key, value in ex4_pricing_keys().items()})
        out.sources["ex4_pricing"] = "the paper's printed values (studies/paper_values.py)"
    _bootstrapped(folder, results, out)
    _self_recomputing(folder, results, out)
    from probecommit.studies.explain.study import plain

    out.values = {key: plain(value) for key, value in out.values.items()}  # as the explain step publishes it
    return out



def _stored_summaries(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """``STORED_SUMMARIES``' keys, each group from its stored table; published keys need their rows."""
    import importlib

    for group, name, module in STORED_SUMMARIES:
        if not (folder / name).is_file():
            if results.get(group):
                out.consistency.append((False, f"explain/{name}: missing (the rows {group}'s keys are recomputed from)"))
            continue
        summary = importlib.import_module(f"probecommit.studies.explain.{module}").summary
        for key, value in summary(pd.read_parquet(folder / name)).items():
            out.values[f"{group}.{key}"] = value
        out.sources[group] = name


def _self_recomputing(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """``SELF_RECOMPUTING``'s groups, each module's ``recompute`` from its own stored rows."""
    import importlib

    for module in SELF_RECOMPUTING:
        values, sources, problems = importlib.import_module(f"probecommit.studies.explain.{module}").recompute(
            folder, results)
        out.values.update(values)
        out.sources.update(sources)
        out.consistency.extend((False, problem) for problem in problems)


def _ex4_cone(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """2-D push's Table II rows under the pyramidal cone from the stored re-executed rows
    (``studies.explain.ex4_cone.keys``); the premise's probe difference is an engine measurement (traced)."""
    from probecommit.studies.explain import ex4_cone

    published = results.get("ex4_cone", {})
    if not (folder / ex4_cone.STORED).is_file() or "premise_max_probe_difference_m" not in published:
        return
    setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]["bootstrap"]
    boot = dict(resamples=int(setup["resamples"]), seed=int(setup["seed"]))
    premise = float(published["premise_max_probe_difference_m"])
    for key, value in ex4_cone.keys(pd.read_parquet(folder / ex4_cone.STORED), premise, boot).items():
        if key != "premise_max_probe_difference_m":
            out.values[f"ex4_cone.{key}"] = value
    out.sources["ex4_cone"] = ex4_cone.STORED
def _bootstrapped(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """``BOOTSTRAPPED``'s groups from their stored rows, each module's ``recompute`` given the insertion
    study's bootstrap settings; published keys need their stored rows (``STORED_BY_GROUP``)."""
    import importlib

    setup = folder.parent / "insertion" / "results.json"
    if not setup.is_file():
        return
    b = json.loads(setup.read_text())["results"]["setup"]["bootstrap"]
    boot = dict(resamples=int(b["resamples"]), seed=int(b["seed"]))
    for name in BOOTSTRAPPED:
        module = importlib.import_module(f"probecommit.studies.explain.{name}")
        for key, (value, source) in module.recompute(folder, results, boot).items():
            out.values[key], out.sources[key] = value, source
        for group, stored in module.STORED_BY_GROUP.items():
            if results.get(group) and not (folder / stored).is_file():
                out.consistency.append((False, f"explain/{stored}: missing (the rows {group}'s keys are recomputed from)"))


def _schedules(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """The schedules' pools, failures and surprise AUCs from the stored schedule rows (``stored.pool_keys``); the
    boundary fault, whole-cluster and Test C escapes and the test runs' strata from the insertion study's
    stored episodes and fault episodes (``stored.harness_keys``), with the generator's expected share as
    published (traced: it is a property of fresh instance draws)."""
    from probecommit.studies.explain import stored
    from probecommit.studies.explain.study import load_explain_config

    insertion = folder.parent / "insertion"
    setup = json.loads((insertion / "results.json").read_text())["results"]["setup"]
    schedules = pd.read_parquet(folder / stored.SCHEDULES)
    for group, values in stored.pool_keys(schedules, setup["bootstrap"]).items():
        out.values.update({f"{group}.{key}": v for key, v in values.items()})
        out.sources.update(dict.fromkeys((f"{group}.{key}" for key in values), stored.SCHEDULES))
    ep = pd.read_parquet(insertion / "episodes.parquet")
    runs = {name: part.drop(columns="run").reset_index(drop=True) for name, part in ep.groupby("run", sort=False)}
    expected = results.get("instance_generator", {}).get("B_test_random.expected_share")
    keys = stored.harness_keys(pd.read_parquet(insertion / "faults_episodes.parquet"), runs, schedules,
                               k_cover=len(setup["cover_schedule"]), k_random=int(setup["k_random"]),
                               edge=float(load_explain_config()["stratum_edge_mm"]), boot=setup["bootstrap"],
                               expected=0.3 if expected is None else float(expected))
    for group, values in keys.items():
        out.values.update({f"{group}.{key}": v for key, v in values.items()})
        out.sources.update(dict.fromkeys((f"{group}.{key}" for key in values),
                                         f"insertion/episodes.parquet, faults_episodes.parquet and {stored.SCHEDULES}"))


def _calibration_rows(folder: Path, out: Recomputed) -> None:
    """The margins, thresholds, their intervals and strata from the stored per-instance calibration rows
    (``calibration_rows.margin_rule_keys``); the random-probe gates and the calibration under the paper's schedule
    from the explain step's stored commits (``gates_from_commits``, ``calibration_from_tables``: the functions
    ``gates`` and ``calibrate`` end in) and runs; the simultaneous thresholds from the stored episodes."""
    from probecommit.runner.calibration import calibration_from_tables, gates_from_commits
    from probecommit.studies.explain import calibration_rows as cr
    from probecommit.studies.explain.study import load_explain_config

    insertion = folder.parent / "insertion"
    setup = json.loads((insertion / "results.json").read_text())["results"]["setup"]
    boot = dict(resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))
    alpha, cfg = float(setup["alpha"]), load_explain_config()
    keys: dict[str, tuple[dict[str, dict[str, Any]], str]] = {}
    names = ("margin_per_gamma.parquet", cr.MARGIN_INSTANCES, cr.MARGIN_SUMS)
    if all((folder / name).is_file() for name in names):
        keys["margins"] = (cr.margin_rule_keys(*(pd.read_parquet(folder / name) for name in names), alpha=alpha,
                                               edge=float(cfg["stratum_edge_mm"]), boot=boot), ", ".join(names))
    if (folder / cr.COMMITS).is_file() and (folder / cr.EPISODES).is_file():
        commits = {name: part.reset_index(drop=True) for name, part in pd.read_parquet(folder / cr.COMMITS).groupby("calibration")}
        ep = pd.concat([pd.read_parquet(insertion / "episodes.parquet"), pd.read_parquet(folder / cr.EPISODES)], ignore_index=True)
        runs = {name: part.drop(columns="run").reset_index(drop=True) for name, part in ep.groupby("run", sort=False)}
        cover = list(range(1, len(setup["cover_schedule"]) + 1))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a margin search that settles on the grid's end (quick runs)
            raw = commits["gates_random"]
            budgets = sorted(int(k) for k in raw.loc[raw["request"] == "raw", "k"].unique())
            gates = gates_from_commits(raw, runs["B_cal_random"], alpha, budgets, **boot)
            cal = calibration_from_tables(commits["paper_schedule"], runs[cr.PAPER_CAL], runs[cr.PAPER_TEST], alpha, cover, **boot)
        source = f"{cr.COMMITS} and {cr.EPISODES} (with insertion/episodes.parquet)"
        keys["gates"] = (cr.random_gate_keys(gates), source)
        keys["paper"] = (cr.paper_calibration_keys(cal), source)
        keys["thresholds"] = (cr.threshold_keys(runs, list(cfg["random_budgets"]), cover, alpha), source)
    for values, source in keys.values():
        for group, part in values.items():
            out.values.update({f"{group}.{key}": v for key, v in part.items()})
            out.sources.update(dict.fromkeys((f"{group}.{key}" for key in part), source))


def _protocol(folder: Path) -> tuple[dict[str, Any], dict[str, int]]:
    """The insertion study's ``setup`` and its bootstrap settings (the protocol's, which the explain step uses)."""
    setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]
    return setup, dict(resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))


def _publish(out: Recomputed, group: str, keys: dict[str, Any], source: str) -> None:
    out.values.update({f"{group}.{key}": v for key, v in keys.items()})
    out.sources.update(dict.fromkeys((f"{group}.{key}" for key in keys), source))


def _replays(folder: Path, out: Recomputed) -> None:
    """``robust.*`` from the stored mixture replays (``robust_rows.keys``: Test C's deployed rows from the insertion
    study's stored episodes, the harness's optimism from its robust filters recomputed from their stored rows, as
    ``_robust``); ``missing.surprise_variants.*`` from the stored surprise readings and schedule rows."""
    from probecommit.studies.explain import robust_rows, surprise_variants
    from probecommit.studies.explain.study import surprise_variant_keys

    insertion = folder.parent / "insertion"
    setup, boot = _protocol(folder)
    if (folder / robust_rows.STORED).is_file() and (insertion / "robust_episodes.parquet").is_file():
        harness = Recomputed()
        _robust(insertion, setup, boot, harness)
        ep = pd.read_parquet(insertion / "episodes.parquet")
        dep = ep[(ep["run"] == "C_random") & (ep["method"] == "probe_robust") & (ep["status"] == "ok")
                 & (ep["k"] == int(setup["k_random"]))].drop(columns="run").reset_index(drop=True)
        _publish(out, "robust", robust_rows.keys(pd.read_parquet(folder / robust_rows.STORED), dep, harness.values["robust"], boot),
                 f"{robust_rows.STORED}, insertion/episodes.parquet and insertion/robust_episodes.parquet")
    if (folder / surprise_variants.STORED).is_file() and (folder / "schedule_episodes.parquet").is_file():
        keys = surprise_variant_keys(pd.read_parquet(folder / surprise_variants.STORED),
                                     pd.read_parquet(folder / "schedule_episodes.parquet"), len(setup["cover_schedule"]), boot)
        _publish(out, "missing", keys, f"{surprise_variants.STORED} and schedule_episodes.parquet")


def _searches(folder: Path, out: Recomputed) -> None:
    """``searches.*`` (``more.search_keys`` of the stored cover-search rows and the insertion study's stored tuning
    rows), with the insertion study's cover-search candidates checked against the same rows; ``grasp_signs.*`` and
    ``committed_pool.resplits.paper_schedule.*`` from their stored rows."""
    from probecommit.studies.explain import grasp_x, resplits, searches
    from probecommit.studies.explain.more import search_keys

    insertion = folder.parent / "insertion"
    if (folder / searches.COVER_STORED).is_file() and (insertion / "robust_episodes.parquet").is_file():
        cover = pd.read_parquet(folder / searches.COVER_STORED)
        keys = search_keys(cover, pd.read_parquet(insertion / "robust_episodes.parquet"), _protocol(folder)[1])
        _publish(out, "searches", keys, f"{searches.COVER_STORED} and insertion/robust_episodes.parquet (tuning rows)")
        if (insertion / "cover_search.parquet").is_file():
            out.consistency.extend(_cover_candidates(pd.read_parquet(insertion / "cover_search.parquet"), cover))
    if (folder / grasp_x.STORED).is_file():
        _publish(out, "grasp_signs", grasp_x.keys(pd.read_parquet(folder / grasp_x.STORED)), grasp_x.STORED)
    from probecommit.studies.explain import ex4_grasp

    if (folder / ex4_grasp.STORED).is_file():  # publications before it stored these rows trace the keys
        _publish(out, "ex4_grasp", ex4_grasp.keys(pd.read_parquet(folder / ex4_grasp.STORED)), ex4_grasp.STORED)
    if (folder / resplits.STORED).is_file():
        _publish(out, "committed_pool", {f"resplits.paper_schedule.{k}": v for k, v in
                                         resplits.summary(pd.read_parquet(folder / resplits.STORED)).items()}, resplits.STORED)


def _generator(folder: Path, out: Recomputed) -> None:
    """``instance_generator.<run>.*`` from the stored frozen draws (``generator.generator_keys``: the redraws are made
    again from the seeds) and ``draws.analytic_equals_mujoco_escape_k8`` from the fresh draws and the stored
    B_test_random episodes."""
    from probecommit.studies.explain import generator, stored
    from probecommit.studies.explain.study import load_explain_config

    if (folder / generator.STORED).is_file():
        try:
            keys = generator.generator_keys(pd.read_parquet(folder / generator.STORED),
                                            float(load_explain_config()["stratum_edge_mm"]))
        except AssertionError:  # a stored hole that is not its generator's draw for the stored seed
            out.consistency.append((False, f"explain/{generator.STORED}: the stored holes are not the generator's draws "
                                           "for their stored seeds (instance_generator.<run>.* are computed from them)"))
            keys = {}
        out.values.update({f"instance_generator.{key}": v for key, v in keys.items()})
        out.sources.update(dict.fromkeys((f"instance_generator.{key}" for key in keys), generator.STORED))
    insertion = folder.parent / "insertion"
    if (folder / stored.DRAWS).is_file():
        k = int(json.loads((insertion / "results.json").read_text())["results"]["setup"]["k_random"])
        ep = pd.read_parquet(insertion / "episodes.parquet")
        mujoco = ep[(ep["run"] == "B_test_random") & (ep["method"] == "probe_robust") & (ep["status"] == "ok") & (ep["k"] == k)]
        for key, value in generator.analytic_equals_mujoco(pd.read_parquet(folder / stored.DRAWS), mujoco).items():
            out.values[f"instance_generator.{key}"] = value
            out.sources[f"instance_generator.{key}"] = f"{stored.DRAWS} and insertion/episodes.parquet"


def _cover_candidates(frozen: pd.DataFrame, rows: pd.DataFrame) -> list[tuple[bool, str]]:
    """The insertion study's cover-search candidates (failure and aim error per schedule) against the explain step's
    stored per-episode rows of the same search (``studies.cover_search.candidate_episodes``), candidate by candidate."""
    means = rows.groupby("schedule", sort=False)[["failure", "aim_error"]].mean()
    out = []
    for row in frozen.to_dict("records"):
        schedule = json.dumps([float(u) for u in json.loads(str(row["schedule"]))])
        if schedule not in means.index:
            continue  # a quick search scores the first candidates only
        for column in ("failure", "aim_error"):
            mine = float(means.loc[schedule, column])
            out.append((abs(mine - float(row[column])) <= 1e-12, f"insertion/cover_search.parquet: {schedule} {column} = "
                        f"{row[column]} but explain/cover_search_episodes.parquet's rows give {mine}"))
    return out


def _gru_copies(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """``gru.*`` but the retrained seed's tolerance: the GRU study's summary recomputed from its stored
    ``gru_episodes.parquet`` (``summarize_gru``, as ``gru`` above) and the explain step's ``summary_keys`` of it."""
    from probecommit.studies.explain.gru import summary_keys
    from probecommit.studies.explain.study import load_explain_config
    from probecommit.studies.gru import load_gru_config, summarize_gru

    study = folder.parent / "gru"
    if not results.get("gru", {}).get("available") or not (study / "gru_episodes.parquet").is_file():
        return
    published = json.loads((study / "results.json").read_text())["results"]
    cfg = load_gru_config()
    per_episode = pd.read_parquet(study / "gru_episodes.parquet")
    summary = summarize_gru(per_episode, published.get("bootstrap") or cfg["bootstrap"],
                            float(published.get("equivalence_margin", cfg["equivalence_margin"])))
    setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]["bootstrap"]
    boot = dict(resamples=int(setup["resamples"]), seed=int(setup["seed"]))
    for key, value in summary_keys(summary, per_episode, boot, load_explain_config()["gru_paper_interval"]).items():
        out.values[f"gru.{key}"] = value
    out.sources["gru"] = "gru/gru_episodes.parquet"


def _scan_copies(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """``engines_x`` and ``physx_capture.ours.*`` from the engines study's scan summaries, recomputed from its stored
    ``engine_scans.parquet`` (``studies.engines.scan_summaries``), and ``physx_capture.emulated.*`` from the stored
    emulated-scene rows, through the explain step's functions."""
    from probecommit.studies.engines import scan_summaries
    from probecommit.studies.explain import engines_x

    path = folder.parent / "engines" / "engine_scans.parquet"
    if (folder / engines_x.EMULATED).is_file():
        from probecommit.studies.explain.study import load_explain_config

        setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]["bootstrap"]
        scale = float(load_explain_config()["physx_emulation"]["capture_scale"])
        keys = engines_x.emulated_keys(pd.read_parquet(folder / engines_x.EMULATED), scale, setup)
        out.values.update({f"physx_capture.{key}": v for key, v in keys.items()})
        out.sources["physx_capture.emulated"] = engines_x.EMULATED
    if not path.is_file():
        return
    scans = scan_summaries(pd.read_parquet(path))
    groups = {"engines_x": engines_x.keys(scans) if results.get("engines_x") else {},
              "physx_capture": engines_x.physx_ours(scans) if results.get("physx_capture") else {}}
    for group, values in groups.items():
        out.values.update({f"{group}.{key}": v for key, v in values.items()})
        out.sources.update(dict.fromkeys((f"{group}.{key}" for key in values), "engines/engine_scans.parquet"))


def _engine_keys(folder: Path, results: dict[str, Any], ep: pd.DataFrame, out: Recomputed) -> None:
    """The PhysX coverage (``stored.physx_coverage_keys``) and PyBullet's stored escapes with the spread of the
    stored per-draw escapes (``pybullet_x.stored_keys``), from the engines study's stored episodes."""
    from probecommit.studies.explain import pybullet_x, stored

    setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]
    k = int(setup["k_random"])
    for key, value in stored.physx_coverage_keys(ep[ep["engine"] == "sapien"], k).items():
        out.values[f"missing.{key}"] = value
        out.sources[f"missing.{key}"] = "engines/engine_episodes.parquet"
    deployed = ep[(ep["engine"] == "pybullet") & (ep["variant"] == "deployed")]
    published = "draws.escape_k8.count" in results.get("pybullet_escape", {})
    if "emulated.escape_k1" in results.get("pybullet_escape", {}) and not (folder / pybullet_x.EMULATED).is_file():
        out.consistency.append((False, f"explain/{pybullet_x.EMULATED}: missing (the rows pybullet_escape.emulated.* "
                                       "are recomputed from)"))
    if published and not (folder / pybullet_x.STORED).is_file():  # published draws need their stored rows
        out.consistency.append((False, f"explain/{pybullet_x.STORED}: missing (the per-draw escapes "
                                       "pybullet_escape.draws.escape_k8.* are recomputed from)"))
    if len(deployed) and (folder / pybullet_x.STORED).is_file():
        boot = dict(resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))
        for key, value in pybullet_x.stored_keys(deployed, pd.read_parquet(folder / pybullet_x.STORED), k, boot).items():
            out.values[f"pybullet_escape.{key}"] = value
        out.sources["pybullet_escape"] = f"engines/engine_episodes.parquet and {pybullet_x.STORED}"
    if len(deployed) and (folder / pybullet_x.EMULATED).is_file():
        boot = dict(resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))
        for key, value in pybullet_x.emulated_keys(pd.read_parquet(folder / pybullet_x.EMULATED), deployed, k, boot).items():
            out.values[f"pybullet_escape.{key}"] = value
            out.sources[f"pybullet_escape.{key}"] = f"{pybullet_x.EMULATED} and engines/engine_episodes.parquet"


def _cost_copies(folder: Path, out: Recomputed) -> None:
    """``missing.cost_of_calibration.*``: Table IV's paired differences recomputed from the insertion study's
    stored commits and episodes (``_calibrated``), keyed as the explain step keys its copy (``cost_keys``)."""
    from probecommit.studies.explain.study import cost_keys

    insertion = folder.parent / "insertion"
    if not (insertion / COMMITS).is_file():
        return
    from probecommit.runner.calibration import calibration_from_tables
    from probecommit.studies.insertion import CALIBRATIONS

    setup = json.loads((insertion / "results.json").read_text())["results"]["setup"]
    ep = pd.read_parquet(insertion / "episodes.parquet")
    runs = {name: part.drop(columns="run").reset_index(drop=True) for name, part in ep.groupby("run", sort=False)}
    commits = pd.read_parquet(insertion / COMMITS)
    cal_run, test_run = CALIBRATIONS["cover"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a margin search that settles on the grid's end (quick runs)
        cal = calibration_from_tables(commits[commits["calibration"] == "cover"].reset_index(drop=True), runs[cal_run],
                                      runs[test_run], float(setup["alpha"]), CALIBRATION_BUDGETS["cover"],
                                      resamples=int(setup["bootstrap"]["resamples"]), seed=int(setup["bootstrap"]["seed"]))
    for key, value in cost_keys(cal.cost_differences.to_dict("records")).items():
        out.values[f"missing.{key}"] = value
    out.sources["missing.cost_of_calibration"] = f"insertion/{COMMITS} and insertion/episodes.parquet"


def _breadth_prior(folder: Path, results: dict[str, Any], out: Recomputed) -> None:
    """Table II's rows and prices at each prior width from the stored sweep rows, with the frozen row (s = 1)
    from the published breadth and cost studies where the explain step used it (a full run), and the span
    summary (``studies.explain.breadth.sweep_keys``); the bootstrap settings are the insertion study's (the
    protocol's, which the explain step uses)."""
    from probecommit.studies.explain.breadth import frozen_row_from, sweep_keys

    setup = json.loads((folder.parent / "insertion" / "results.json").read_text())["results"]["setup"]["bootstrap"]
    stored = pd.read_parquet(folder / EXPLAIN_BREADTH)
    published = results.get("breadth_prior", {})
    frozen = {str(f): frozen_row_from(folder.parent / "breadth" / "results.json", folder.parent / "cost" / "results.json",
                                      str(f)) if f"{f}.s1.blind_bayes" in published else None
              for f in stored["family"].unique()}
    for key, value in sweep_keys(stored, frozen, dict(resamples=int(setup["resamples"]), seed=int(setup["seed"]))).items():
        out.values[f"breadth_prior.{key}"] = value
    out.sources["breadth_prior"] = f"{EXPLAIN_BREADTH} (and breadth/, cost/results.json for s = 1)"


#: The explain step's stored prior-sweep rows (``studies.explain.breadth.STORED``).
EXPLAIN_BREADTH = "breadth_prior_episodes.parquet"
#: The explain step's stored per-seed mixture rows (``studies.explain.mixture_x.STORED``).
EXPLAIN_MIXTURE = "mixture_noise_seeds.parquet"
#: The explain step's stored rig redraws (``studies.explain.rig.STORED_SESSIONS``, ``STORED_BOUNDARY``).
EXPLAIN_RIG = ("rig_redraws_sessions.parquet", "rig_redraws_boundary.parquet")
#: The explain step's stored calibration rows of ex5 (``studies.explain.ex5_calibration.STORED``).
EXPLAIN_EX5 = "ex5_calibration_rows.parquet"
#: ex9's stored rows (``studies.explain.ex9_calibration.STORED``: coverage splits, cost splits, E82's budgets).
EXPLAIN_EX9 = "ex9_calibration_rows.parquet"
#: ex12's stored rows (``studies.explain.ex12_distinct.STORED``: E100's budget-k rows without replacement).
EXPLAIN_EX12 = "ex12_distinct_rows.parquet"
#: ex12's stored rows (``studies.explain.ex12_simultaneous.STORED``: E101's re-splits under the simultaneous level).
EXPLAIN_EX12_SIM = "ex12_simultaneous_rows.parquet"
#: ex15's stored rows (``studies.explain.ex15_readings.STORED``: E118's re-splits under every reading).
EXPLAIN_EX15 = "ex15_readings_rows.parquet"
#: ex15's stored rows (``studies.explain.ex15_union.STORED``: E119's re-splits of the literal Split B pool).
EXPLAIN_EX15_UNION = "ex15_union_rows.parquet"
#: ex18's stored rows (``studies.explain.ex18_share.STORED``: E132's per-split optimistic readings of two pools).
EXPLAIN_EX18_SHARE = "ex18_share_rows.parquet"
#: ex18's stored rows (``studies.explain.ex18_grasp.STORED``: E133's grasp reruns under each force ceiling).
EXPLAIN_EX18_GRASP = "ex18_grasp_rows.parquet"
#: ex26's stored rows (``studies.explain.ex26_grasp.STORED``: E178/E179's grasp reruns per squeeze duration).
EXPLAIN_EX26_GRASP = "ex26_grasp_rows.parquet"
#: ex28's stored rows (``studies.explain.ex28_plateau.STORED``: E186's re-splits with the W = 1 plateau as one tie).
EXPLAIN_EX28_PLATEAU = "ex28_plateau_rows.parquet"
#: ex30's stored rows (``studies.explain.ex30_fresh.STORED``: E190's re-split draws, E191's selections and cells).
EXPLAIN_EX30_FRESH = "ex30_fresh_rows.parquet"
#: ex33's stored rows (``studies.explain.ex33_aim.STORED``: E199's re-split outcome draws, E200's cells).
EXPLAIN_EX33_AIM = "ex33_aim_rows.parquet"
#: ex35's stored rows (``studies.explain.ex35_pools.STORED``: E205's fresh pools, E56's three and the rest).
EXPLAIN_EX35_POOLS = "ex35_pools_rows.parquet"
#: ex37's stored rows (``studies.explain.ex37_filters.STORED``: E212's Test C replay, E213's harness draws' arms).
EXPLAIN_EX37_FILTERS = "ex37_filters_rows.parquet"
#: ex36's stored rows (``studies.explain.ex36_coverage.STORED``: E209's per-draw episode coverage, the check first).
EXPLAIN_EX36_COVERAGE = "ex36_coverage_rows.parquet"
#: ex38's stored rows (``studies.explain.ex38_physx.STORED``: E214's and E216's PhysX scan rows per point).
EXPLAIN_EX38_PHYSX = "ex38_physx_rows.parquet"
#: ex40's stored rows (``studies.explain.ex40_solver.STORED``: E226's PhysX scan rows per solver iteration count).
EXPLAIN_EX40_SOLVER = "ex40_solver_rows.parquet"
#: ex39's stored rows (``studies.explain.ex39_pybullet.STORED``: E218's PyBullet scans per plate contact).
EXPLAIN_EX39_PYBULLET = "ex39_pybullet_rows.parquet"
#: ex41's stored rows (``studies.explain.ex41_slop.STORED``: E228's PyBullet scans per contact slop).
EXPLAIN_EX41_SLOP = "ex41_slop_rows.parquet"
#: ex29's stored rows (``studies.explain.ex29_band.STORED``: E187's trajectories, k = 1 surprise and first-tap band).
EXPLAIN_EX29_BAND = "ex29_band_rows.parquet"
#: ex7's stored rows (``studies.explain.ex7.STORED``: the fault surprise rows and the fresh draws).
EXPLAIN_EX7 = ("ex7_fault_surprise.parquet", "ex7_dev_draws.parquet", "ex7_harness_draws.parquet")

#: Explain groups whose keys are one ``summary(rows)`` of one stored table: (group, file, module).
STORED_SUMMARIES = (("mixture_noise", EXPLAIN_MIXTURE, "mixture_x"),
                    ("ex5_calibration", EXPLAIN_EX5, "ex5_calibration"),
                    ("ex9_calibration", EXPLAIN_EX9, "ex9_calibration"),
                    ("ex12_distinct", EXPLAIN_EX12, "ex12_distinct"),
                    ("ex12_simultaneous", EXPLAIN_EX12_SIM, "ex12_simultaneous"),
                    ("ex15_readings", EXPLAIN_EX15, "ex15_readings"),
                    ("ex15_union", EXPLAIN_EX15_UNION, "ex15_union"),
                    ("ex18_share", EXPLAIN_EX18_SHARE, "ex18_share"),
                    ("ex18_grasp", EXPLAIN_EX18_GRASP, "ex18_grasp"),
                    ("ex26_grasp", EXPLAIN_EX26_GRASP, "ex26_grasp"),
                    ("ex28_plateau", EXPLAIN_EX28_PLATEAU, "ex28_plateau"),
                    ("ex30_fresh", EXPLAIN_EX30_FRESH, "ex30_fresh"),
                    ("ex29_band", EXPLAIN_EX29_BAND, "ex29_band"),
                    ("ex33_aim", EXPLAIN_EX33_AIM, "ex33_aim"),
                    ("ex35_pools", EXPLAIN_EX35_POOLS, "ex35_pools"),
                    ("ex37_filters", EXPLAIN_EX37_FILTERS, "ex37_filters"),
                    ("ex36_coverage", EXPLAIN_EX36_COVERAGE, "ex36_coverage"),
                    ("ex38_physx", EXPLAIN_EX38_PHYSX, "ex38_physx"),
                    ("ex39_pybullet", EXPLAIN_EX39_PYBULLET, "ex39_pybullet"),
                    ("ex40_solver", EXPLAIN_EX40_SOLVER, "ex40_solver"),
                    ("ex41_slop", EXPLAIN_EX41_SLOP, "ex41_slop"))

#: Explain modules that recompute their own groups: ``recompute(folder, results)`` gives
#: ``(values, sources, problems)`` (a group published without its stored rows is a problem).
SELF_RECOMPUTING = ("ex7", "ex8", "ex11", "ex16", "ex19", "ex22", "ex25", "ex27", "ex32")

#: Explain modules whose ``recompute(folder, results, boot)`` gives ``{key: (value, stored file)}`` under the
#: insertion study's bootstrap settings, with ``STORED_BY_GROUP`` naming each group's rows.
BOOTSTRAPPED = ("ex6", "ex10", "ex13", "ex14", "ex17", "ex20", "ex21", "ex23", "ex24", "ex31_shift", "ex34_fixed",
                "ex37_adjusted", "ex36_testc", "ex43_setonly")


#: The stored tables each study's numbers are recomputed from: a publication without one fails verify
#: (deleting a table and re-hashing the manifest would otherwise turn its numbers into traced ones).
STORED_TABLES: dict[str, tuple[str, ...]] = {
    "insertion": ("episodes.parquet", "faults_episodes.parquet", COMMITS, "robust_episodes.parquet",
                  "scan.parquet", "scan_grid.parquet", "cover_search.parquet", "resplits.parquet"),
    "breadth": ("breadth_episodes.parquet",),
    "engines": ("engine_episodes.parquet", "engine_scans.parquet"),
    "robot": ("robot_episodes.parquet", SWEEPS),
    "gru": ("gru_episodes.parquet",),
    "beyond": ("beyond_episodes.parquet",),
    "explain": ("margin_per_gamma.parquet", "fresh_draws.parquet", "draw_cells.parquet", EXPLAIN_BREADTH,
                "schedule_episodes.parquet", EXPLAIN_MIXTURE, *EXPLAIN_RIG, "margin_instances.parquet",
                "margin_instance_sums.parquet", "commits.parquet", "episodes.parquet", "physx_emulated_episodes.parquet",
                "robust_replays.parquet", "resplits_paper_schedule.parquet", "surprise_variants.parquet",
                "cover_search_episodes.parquet", "generator_instances.parquet",
                "grasp_analytic_episodes.parquet", EXPLAIN_EX5, *EXPLAIN_EX7, EXPLAIN_EX9),
    # ``pybullet_x.EMULATED`` is required where the engines study's PyBullet run was there (``_engine_keys``).
}

#: Study folder -> its recomputation.
STUDIES: dict[str, Callable[[Path, dict[str, Any]], Recomputed]] = {
    "insertion": insertion, "breadth": breadth, "cost": cost, "engines": engines, "robot": robot, "gru": gru, "beyond": beyond,
    "explain": explain}

#: What each study's recomputation covers, and what is traced only (for the report and the docs).
RECOMPUTED = {
    "insertion": "Table IV (Split A, Split B's cost table and paired differences); t_k and the simultaneous t; "
                 "Table III with its intervals and summary; the margins; Table V (Test C) with its set+margin row; "
                 "escape and episode coverage at k = 1, 8; Table VIII; the fault signatures; the commit gates "
                 "(summary, curves, t, gamma) and Fig. 6's coverage table; the robust filters (tuning, arms); scan; "
                 "cover search; re-split summary",
    "breadth": "Table II (every family but insertion's row, which is the insertion study's); the budget curves",
    "cost": "the probe prices",
    "engines": "Table VI, the paired failure differences at k = 8 (also by name), escape against k (also by name); "
               "the boundary and capture-window scan summaries",
    "robot": "Table VII (simulated rig) and the session's counts, pooled optimism; both fault sweeps, the first "
             "resolved and holds-to boundary sizes",
    "gru": "every number of the GRU table but the training loss",
    "beyond": "the plateau, moves and adaptive tables",
    "explain": "the margin curves' cells; the margins, thresholds, their intervals, shares and strata (per-instance "
               "calibration rows); the random-probe gates and the calibration under the paper's schedule (re-executed "
               "commits); the simultaneous thresholds; the fresh draws' summaries; Table III's and the fault harness's "
               "cells over fresh draws; the schedules' pools, failures and cover surprise AUCs; the surprise variants; "
               "the boundary fault, Test C, whole-cluster escapes and strata; the generator test; the prior sweep's "
               "rows, prices and spans; the mixture against the filter's noise and the mixture replays (robust); the "
               "simulated rig redrawn; the PhysX coverage, capture scans and emulated scene; the cost of calibration; "
               "PyBullet's stored escapes, its emulated scene and that scene's escape over fresh draws; the re-splits under the "
               "paper's schedule; the development searches; grasp on the model-exact scene; the GRU's spread and power; "
               "the PyBullet capture interval; ex5's re-split costs, fresh pools and capture pairs; ex4's single-width "
               "counts, prices from the paper's curve and the pyramidal-cone rows; ex7's fault readings and fresh draws; "
               "ex9's held-out coverage with ties, costs over four pools and the calibrated arm at the paper's margin; "
               "ex10's per-tap boundary replays of PyBullet and the paper's-schedule surprise without the jitter's tail; "
               "ex11's Probe-Robust cells over redrawn truth pools; ex13's surprise AUCs over five draws of the generator "
               "under the paper's schedule and the mixture's cost under every reading of q0's units; "
               "ex14's band decomposition of k = 1 escape and the filter sentence's readings (escape, Table III's "
               "original cells, T36's AUCs); "
               "ex12's Table III original cells under a schedule without replacement and the re-splits under the "
               "budget-simultaneous level; ex15's re-splits under every reading of the paper's sentence, on the frozen "
               "pool and on Split B's pooled halves; ex16's hinge and push1d probed cells with probes that reach the "
               "commit regime; ex17's Table III original arm under the aim tie-break readings (optimism and its "
               "score, model and belief parts) and the cover schedule's first-tap band against T36's escapes; "
               "ex19's darts blind cells over redrawn truths at every width of the prior sweep; ex18's "
               "optimistic-split counts against the paper's and grasp under each force ceiling; ex22's hinge and push1d "
               "probed cells decided again on the exact posterior of the stored readings and the hinge's probe magnitudes swept; "
               "ex20's Table III original arm post-stratified on the design's exposure to the misread band; ex21's "
               "paper's-schedule band trajectories under the unstated weight and jitter-timing readings and without "
               "the first resampling's jitter; ex23's fresh draws post-stratified at every budget and the calibrated "
               "arm under a band-weighted threshold and margin (its re-executed commits stored); ex24's the same "
               "draws with the first tap's jitter removed alone, the jitter read as a variance, and post-stratified "
               "to the first tap's band exposure; ex25's hinge and push1d probed cells with probes uniform over the "
               "probe interval; ex27's hinge row with the commit a torque; ex31's Table III original arm read one tap later, "
               "post-stratified as ex20's; ex34's Table III original arm with one fixed tap (-12 or 0 mm) before the "
               "random ones; ex32's push1d, hinge and push2d probed cells against the action grid's floor "
               "at each truth; ex35's re-split statistics over twelve fresh pools; ex37's commit gates' pools under the "
               "paper's schedule (the adjusted gate's ratio and interval; threshold and margin traced) and the robust "
               "filters' optimism on Test C and over the harness draws; ex38's PhysX scans at each contact and rest "
               "offset swept; ex39's PyBullet scans over plate contact stiffnesses; ex40's PhysX scans at each solver "
               "iteration count swept; ex41's PyBullet scans over contact slops; ex43's Table III calibrated arm "
               "re-committed at the published levels without the margin (and with it, as a check)",
}
TRACED_ONLY = {
    "insertion": "the stored rows themselves (episodes, re-executed commits, replays); the re-split rows; the cover "
                 "search's candidates (checked against the explain target's stored rows of the same search when it is "
                 "published); the scan offsets",
    "engines": "the engine-query counts",
    "robot": "the replay reproduction fraction",
    "gru": "the training loss",
    "explain": "the stored rows themselves (re-commits, replays, redraws, emulated scenes: run directories a "
               "publication does not hold); the retrained GRU seed's parameter differences (a training run); "
               "the paper's PyBullet values (docs/verify.md); explain.md is "
               "rendered again from results.json",
    "figures": "Fig. 1a/1c and Fig. 3 (scene renders from run directories); Fig. 2 is drawn again from code",
    "setup": "Table I (rendered again from the registry and frozen configs; its counts are the configs', not a "
             "quick run's stored rows)",
}


#: Why a results.json number is traced only (hashed, range-checked, rendered again into every text that prints it,
#: but not recomputed), by kind; ``verify``'s headline counts the traced-only numbers by these kinds.
TRACED_KINDS = {
    "measured": "a measurement of the run itself (engine-query count, a replay's agreement with the log's "
                "decisions, the frozen scan offset and its copy in ex6's scene, the cone premise's largest probe "
                "difference): no stored table implies it",
    "training": "needs a training run (the GRU's training loss, a retrained seed's parameters)",
    "engine rows": "the frozen choice a search over engine rollouts made, beside its stored per-candidate rows "
                   "(the frozen cover schedule and its rank, the re-split pool's size)",
    "scene render": "the numbers of a scene render drawn from run directories (Fig. 1a/1c, Fig. 3)",
    "setting": "a setting printed beside the results (alpha, sigma, budgets, seeds, resamples, the frozen config)",
    "paper value": "the paper's value printed beside ours (checked against the seed text by the paper-values test)",
    "not stored": "a summary of rows the publication does not store (docs/verify.md lists each)",
}
#: (study, regular expression on the dotted results.json key, kind): the first match names a traced number's kind;
#: a number no pattern matches is "not stored".
TRACED_PATTERNS: tuple[tuple[str, str, str], ...] = (
    ("gru", r"^training_", "training"),
    ("explain", r"^gru\.(retrain_|threads_)", "training"),
    ("explain", r"^pybullet_escape\.paper_", "paper value"),
    ("robot", r"^replay_reproduced_fraction$", "measured"),
    ("engines", r"\.engine_calls(\.|$)", "measured"),
    ("insertion", r"^scan\.frozen_delta$", "measured"),
    ("explain", r"^(ex6_probe_rule\.boundary_offset|ex4_cone\.premise_max_probe_difference_m)$", "measured"),
    ("insertion", r"^(cover\.frozen|resplits\.pool)", "engine rows"),
    ("figures", r"^(fig1|scenes)\.", "scene render"),
    ("*", r"^(setup|settings|bootstrap|config)\.|^(sweep_resamples|equivalence_margin)$|^instance_generator\.\w+\.seeds$",
     "setting"),
)


def traced_kind(study: str, key: str) -> str:
    """Why a traced-only results.json number (``key`` dotted) is not recomputed (a ``TRACED_KINDS`` key)."""
    import re

    for where, pattern, kind in TRACED_PATTERNS:
        if where in (study, "*") and re.search(pattern, key):
            return kind
    return "not stored"
