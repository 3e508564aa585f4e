"""``probecommit reproduce insertion``: every MuJoCo insertion table and figure.

The steps, in the paper's order of dependence: the boundary scan and the cover
schedule search on the development instances (both frozen into the protocol), the
rollouts of every instance set, the replays under the corrected model, calibration,
the Test C confirmation, the fault harness, the robust filters and the re-split
study. Each step writes its tables to ``results/`` as Markdown and every number
into ``results.json``; ``REPRODUCTION.md`` is generated from those.

The study computes; how its tables and figures are drawn is the report layer's, handed in as
a :class:`Render` (``report.insertion_study`` supplies it), so studies never import report.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
import pandas as pd

from probecommit.runner.calibration import calibrate
from probecommit.audit.stats import cluster_bootstrap_mean, paired_bootstrap
from probecommit.audit.surprise import surprise_auc
from probecommit.process.memory import release_free_heap, trim_heap
from probecommit.runner.build import build_model, build_simulator
from probecommit.runner.replay import LoadedRun, RunBeliefs, load_run, replay_episodes, replay_run, trace_for_run
from probecommit.runner.study import run_study
from probecommit.tasks.insertion import make_simulator
from probecommit.studies.cover_search import search_cover_schedule
from probecommit.studies.faults import FAULTS, fault_arms, run_fault_harness, signature_table
from probecommit.studies.protocol import DEFAULT_PROTOCOL, Protocol, load_protocol
from probecommit.studies.robust import final_failure, robust_candidates, tune_robust_filters
from probecommit.studies.scan import scan_development
from probecommit.store.rundir import RunDir
from probecommit.store.safefile import write_text, write_with

Progress = Callable[[str, int, int], None]


def no_progress(step: str, done: int, total: int) -> None:
    return None


@dataclass(frozen=True)
class Render:
    """How the study's tables and figures are drawn (the report layer's functions).

    Attributes:
        tables: Table key -> ``(results, out) -> Markdown``.
        scan_figure, fault_signatures, decisive_tap_figure, decision_figure: Each draws its figure and
            returns its path (``decisive_tap_figure`` from Fig. 4b's data series, :func:`decisive_tap_series`);
            returns its path.
    """

    tables: Mapping[str, Callable[[dict, Path], str]]
    scan_figure: Callable[..., Path]
    fault_signatures: Callable[..., Path]
    decisive_tap_figure: Callable[..., Path]
    decision_figure: Callable[..., Path]


def with_model(config: Any, **fields: Any) -> Any:
    """``config`` with its family's model section updated by ``fields``.

    ``StudyConfig.model`` is a property over ``task.model``: a copy must update the task
    section (``model_copy(update={"model": ...})`` on the study config changes nothing).
    """
    task = config.task.model_copy(update={"model": config.task.model.model_copy(update=fields)})
    return config.model_copy(update={"task": task})


@dataclass
class Reproduction:
    """Where everything went, and the numbers."""

    root: Path
    results: dict[str, Any] = field(default_factory=dict)
    tables: dict[str, str] = field(default_factory=dict)
    figures: dict[str, str] = field(default_factory=dict)
    engine_calls: dict[str, int] = field(default_factory=dict)
    wall_s: float = 0.0

    def add_calls(self, calls: dict[str, int]) -> None:
        for key, value in calls.items():
            self.engine_calls[key] = self.engine_calls.get(key, 0) + int(value)


#: Runs whose episodes the publication stores (``episodes.parquet``): verify recomputes from them.
RECOMPUTED_RUNS = ("A_cover", "B_cal_cover", "B_cal_random", "B_test_cover", "B_test_random", "C_random",
                   "C_random_corrected", "C_cover", "C_cover_corrected", "B_cal_cover_corrected")
#: The re-executed commits verify recomputes the calibrated numbers and the gates from
#: (``runner.calibration.Recorder``): calibration name -> (calibration run, test run).
CALIBRATIONS = {"cover": ("B_cal_cover", "B_test_cover"), "random": ("B_cal_random", "B_test_random"),
                "testc_old": ("B_cal_cover", "C_cover"), "testc_corrected": ("B_cal_cover_corrected", "C_cover_corrected"),
                "gates": ("B_cal_cover", "B_test_cover")}
COMMITS_FILE = "commits.parquet"
#: The scan readings of the instance Fig. 4a draws.
SCAN_GRID = "scan_grid.parquet"
#: The episode columns the recomputed numbers read (``z_true``: the explain target stratifies the fault
#: harness's episodes by where the hole is).
STORED_COLUMNS = ("instance_id", "repeat", "k", "method", "status", "predicted", "realized", "covered", "escaped",
                  "score_s", "max_surprise", "z_true")


def store_episodes(episodes: pd.DataFrame, path: Path, extra: tuple[str, ...] = ()) -> None:
    """Write the columns verify reads, strings as dictionaries (a few bytes an episode)."""
    table = episodes[[*extra, *STORED_COLUMNS]].reset_index(drop=True)
    write_with(path, lambda buf: table.to_parquet(buf, compression="zstd", index=False))


#: The robust filters' rows (``robust_summary`` reads them): each tuning candidate's final-budget rows
#: on the development run and each arm's rows at the final budget.
ROBUST_FILE = "robust_episodes.parquet"
ROBUST_COLUMNS = ("instance_id", "repeat", "k", "method", "status", "predicted", "realized", "covered", "escaped")


def robust_summary(tuning: pd.DataFrame, arms: dict[str, pd.DataFrame], kmax: int, boot: dict[str, int]) -> dict[str, Any]:
    """The robust-filter results: the tuning table, the chosen values, the deployed filter's metrics and each
    chosen filter's with its paired failure difference, and the mixture's cost when the model is right
    (one function for the study and for verify, which passes the stored rows)."""
    chosen = {row.family: row.value for row in tuning[tuning.chosen].itertuples()}
    res = {"tuning": tuning.to_dict("records"), "chosen": chosen,
           "deployed": episode_metrics(arms["deployed"], kmax, **boot)}
    for family, value in chosen.items():
        m = episode_metrics(arms[family], kmax, **boot)
        res[family] = {"value": value, **m, "failure_diff": paired(arms["deployed"], arms[family], kmax, "realized", **boot)}
    if "mixture" in chosen:
        res["mixture_cost_when_right"] = [float(probe_rows(arms["base"], kmax)["realized"].mean()),
                                          float(probe_rows(arms["mixture_right"], kmax)["realized"].mean())]
    return res


#: Fig. 4b's data: both beliefs' particles after the decisive tap, with the truth, the tap and its reading.
DECISIVE_TAP = "decisive_tap.parquet"


def decisive_tap_series(z_deployed, w_deployed, z_corrected, w_corrected, z_true: float, tap: float, reading: float,
                        k: int) -> pd.DataFrame:
    """Fig. 4b's data series, one table: each model's particles and weights (``model``), the scalars on every row."""
    parts = [pd.DataFrame({"model": name, "z": np.asarray(z, float), "weight": np.asarray(w, float)})
             for name, z, w in (("deployed", z_deployed, w_deployed), ("corrected", z_corrected, w_corrected))]
    return pd.concat(parts, ignore_index=True).assign(z_true=z_true, tap=tap, reading=reading, k=int(k))


def store_commits(commits: dict[str, list[pd.DataFrame]], path: Path) -> None:
    """The calibrations' re-executed rows (``runner.calibration.Recorder``), one zstd table with a
    ``calibration`` column; the columns a request does not read are empty (strings are stored as
    Parquet dictionaries, a few bytes a row)."""
    frames = [pd.concat(parts, ignore_index=True).assign(calibration=name) for name, parts in commits.items() if parts]
    if not frames:
        return
    table = pd.concat(frames, ignore_index=True)
    table = table[["calibration", "request", "gamma", *[c for c in table.columns if c not in ("calibration", "request", "gamma")]]]
    write_with(path, lambda buf: table.to_parquet(buf, compression="zstd", index=False))


def signature_points(signatures: pd.DataFrame) -> dict[str, Any]:
    """Fig. 7's data by fault and budget, so a claim can name one point (``fault_signatures.prior.1``);
    verify recomputes it from the stored fault episodes."""
    return {str(fault): {str(int(r["k"])): {c: float(r[c]) for c in ("escape", "coverage", "optimism", "failure")}
                         for _, r in part.iterrows()} for fault, part in signatures.groupby("fault", sort=False)}


def signature_n(episodes: pd.DataFrame, kmax: int) -> int:
    """Episodes behind each point of Fig. 7 (its caption prints it; verify draws the figure again with it)."""
    return int(((episodes.arm == "fault") & (episodes.fault == FAULTS[0]) & (episodes.k == kmax)
                & (episodes.method == "probe_robust")).sum())


def probe_rows(episodes: pd.DataFrame, k: int | None = None) -> pd.DataFrame:
    out = episodes[(episodes.method == "probe_robust") & (episodes.status == "ok")]
    return out if k is None else out[out.k == k]


def subset_run(loaded: LoadedRun, instance_ids, beliefs: RunBeliefs | None = None) -> LoadedRun:
    """The same run restricted to some instances (for re-splits of one pool).

    Args:
        beliefs: The whole run's beliefs (one chunk); the subset then takes its episodes'
            beliefs from them instead of recomputing them.
    """
    keep = set(instance_ids)
    return LoadedRun(
        loaded.path, loaded.config,
        loaded.instances[loaded.instances.instance_id.isin(keep)].reset_index(drop=True),
        loaded.probes[loaded.probes.instance_id.isin(keep)].reset_index(drop=True),
        loaded.episodes[loaded.episodes.instance_id.isin(keep)].reset_index(drop=True),
        loaded.engine_cache, loaded.manifest, None if beliefs is None else beliefs.restrict(keep),
    )


#: The calibrated arm's name in a calibration's cost table and arms.
SET_MARGIN = "set calibration + margin"


def setmargin_failure(cal: Any) -> float:
    """A calibration's failure with set calibration and the margin (its cost table's row)."""
    row = cal.cost[cal.cost["setting"] == SET_MARGIN]
    return float(row["failure"].iloc[0])


def setmargin_paired(cal_old: Any, cal_new: Any, resamples: int, seed: int) -> list[float]:
    """``[estimate, lo, hi]`` of old - corrected failure with set calibration and the margin (Table V's last
    row), paired on the test episodes both calibrations committed at the cost budget (the same taps, the
    same instances): the paired cluster bootstrap of Table V's other rows, on each calibration's own arm."""
    base, treat = cal_new.arms[SET_MARGIN], cal_old.arms[SET_MARGIN]
    diff = paired_bootstrap(base, treat, "realized", resamples=resamples, seed=seed)
    return [diff.difference.estimate, diff.difference.lo, diff.difference.hi]


def resplit_table(pool: LoadedRun, alpha: float, count: int, seed: int, k: int, boot_seed: int,
                  progress: Callable[[int], None] | None = None) -> pd.DataFrame:
    """The re-split study's rows: ``count`` random halves of one pool, each calibrated on one half at
    budget ``k`` and tested on the other (level t_k, set+margin failure, held-out cluster coverage,
    whether the margin is optimistic, gamma). The pool's beliefs at ``k`` are computed once for every
    split; the explain target runs the same study on the paper's schedule's pool."""
    ids = pool.instances["instance_id"].to_numpy()
    rng = np.random.default_rng(seed)
    beliefs = RunBeliefs.of(pool, chunk_instances=None, budgets=[k])
    rows = []
    for n in range(count):
        perm = rng.permutation(len(ids))
        half = len(ids) // 2
        cal = subset_run(pool, ids[perm[:half]], beliefs)
        test = subset_run(pool, ids[perm[half:]], beliefs)
        res = calibrate(cal, test, alpha=alpha, budgets=[k], resamples=50, seed=boot_seed + n)
        t3 = res.table3
        rows.append({"split": n, "level": float(res.thresholds[k]), "failure": setmargin_failure(res),
                     "heldout_cluster_coverage": float(t3["cluster_coverage_calibrated"].iloc[0]),
                     "margin_optimistic": bool(t3["optimism_calibrated"].iloc[0] > 0), "gamma": res.margin.gamma})
        if progress:
            progress(n + 1)
        del cal, test, res
        trim_heap()  # a split's copies go back before the next split copies its halves
    return pd.DataFrame(rows)


def coverage_vs_nominal(cal_episodes: pd.DataFrame, test_episodes: pd.DataFrame, k: int,
                        levels: np.ndarray | None = None) -> pd.DataFrame:
    """Fig. 4a's data: held-out cluster coverage against the nominal level 1 - alpha at budget ``k``.

    The threshold is the conformal quantile of the calibration instances' worst-repeat
    scores; coverage is the score identity ``s <= t`` on the test instances (all repeats).
    """
    from probecommit.audit.conformal import conformal_quantile, instance_scores, score_coverage

    levels = np.round(np.arange(0.5, 0.951, 0.05), 2) if levels is None else levels
    cal = instance_scores(cal_episodes[cal_episodes["method"] == "probe_robust"], k).dropna().to_numpy()
    test = test_episodes[(test_episodes["method"] == "probe_robust") & (test_episodes["k"] == k)]
    rows = []
    for level in levels:
        t = conformal_quantile(cal, 1 - level)
        cov = score_coverage(test, min(t, 1e9))
        # An infinite threshold (q = M + 1: too few calibration instances) is stored as NaN with a flag.
        rows.append({"nominal": float(level), "threshold": float(t) if np.isfinite(t) else float("nan"),
                     "threshold_infinite": bool(not np.isfinite(t)),
                     "cluster_coverage": float(cov["cluster_coverage"].iloc[0])})
    return pd.DataFrame(rows)


def episode_metrics(episodes: pd.DataFrame, k: int, resamples: int, seed: int) -> dict[str, Any]:
    """Failure, predicted, optimism, coverage and escape at one budget, with cluster intervals."""
    rows = probe_rows(episodes, k)
    out: dict[str, Any] = {"n": int(len(rows))}
    for name, values in (
        ("failure", rows["realized"].to_numpy(float)),
        ("predicted", rows["predicted"].to_numpy(float)),
        ("optimism", (rows["realized"] - rows["predicted"]).to_numpy(float)),
        ("episode_coverage", rows["covered"].to_numpy(float)),
        ("escape", rows["escaped"].to_numpy(float)),
    ):
        iv = cluster_bootstrap_mean(values, rows["instance_id"].to_numpy(), resamples=resamples, seed=seed)
        out[name] = [iv.estimate, iv.lo, iv.hi]
    return out


def paired(base: pd.DataFrame, treat: pd.DataFrame, k: int, value: str, resamples: int, seed: int) -> list[float]:
    """``[estimate, lo, hi]`` of ``treat - base`` at budget k on identical episodes."""
    b, t = probe_rows(base, k).copy(), probe_rows(treat, k).copy()
    if value == "optimism":
        b["optimism"] = b["realized"] - b["predicted"]
        t["optimism"] = t["realized"] - t["predicted"]
    b[value] = b[value].astype(float)
    t[value] = t[value].astype(float)
    diff = paired_bootstrap(b, t, value, resamples=resamples, seed=seed)
    return [diff.difference.estimate, diff.difference.lo, diff.difference.hi]


class InsertionReproduction:
    """Runs the insertion reproduction step by step into ``root``."""

    #: Instances whose beliefs a calibration or replay holds at once. Half the library default:
    #: a split's calibration then takes two chunks and recomputes its beliefs per commit call
    #: (about +10 % in those steps) but holds half as much, which keeps the whole
    #: reproduction's peak under 400 MB (docs/decisions.md).
    CHUNK_INSTANCES = 48

    def __init__(self, protocol: Protocol, root: Path, render: Render, progress: Progress = no_progress,
                 workers: int = 1) -> None:
        self.p = protocol
        self.render = render
        self.root = Path(root)
        self.runs = self.root / "runs"
        self.out = self.root / "results"
        self.out.mkdir(parents=True, exist_ok=True)
        self.progress = progress
        self.workers = workers
        self.rep = Reproduction(self.root)
        self.boot = dict(resamples=protocol.bootstrap.resamples, seed=protocol.bootstrap.seed)
        self.chunk = dict(chunk_instances=self.CHUNK_INSTANCES)
        self.loaded: dict[str, LoadedRun] = {}
        #: Per calibration (``CALIBRATIONS``), the re-executed rows its results read.
        self.commits: dict[str, list[pd.DataFrame]] = {name: [] for name in CALIBRATIONS}
        # What the tables print about the protocol itself (Table I's row, the fault table's header).
        self.rep.results["setup"] = {
            "engine": protocol.engine, "sigma": protocol.sigma, "k_random": protocol.budgets["random"],
            "cover_schedule": list(protocol.cover_schedule), "n": f"{protocol.instances['B'].count}x{protocol.repeats}",
            "temperature": protocol.faults.temperature, "alpha": protocol.alpha,
            "bootstrap": {"resamples": protocol.bootstrap.resamples, "seed": protocol.bootstrap.seed}}

    # ---------------------------------------------------------------- helpers
    def run(self, name: str, config) -> LoadedRun:
        self.progress(f"run {name}", 0, 1)
        already_done = RunDir(self.runs / name).is_complete()
        # Units one after the other: the MuJoCo runs' engine queries already fill the cores in
        # engine threads, so unit threads gave no time here (111.7 s vs 112.7 s) and 107 MB more peak.
        result = run_study(config, self.runs / name, workers=self.workers, threads=1,
                           progress=lambda d, t: self.progress(f"run {name}", d, t))
        # Count only engine work done now: a complete run from an earlier invocation made no calls.
        if not already_done and result.manifest.get("resumed_units", 0) == 0:
            self.rep.add_calls(result.manifest["engine_calls"])
        self.loaded[name] = load_run(result.run_dir)
        return self.loaded[name]

    def replay(self, source: str, name: str, overrides: dict) -> LoadedRun:
        path = self.runs / name
        fresh = not RunDir(path).is_complete()
        if fresh:
            replay_run(self.runs / source, path, overrides, **self.chunk)
        self.loaded[name] = load_run(path)
        if fresh:
            self.rep.add_calls(self.loaded[name].manifest["engine_calls"])
            release_free_heap()  # a replay held a chunk of beliefs at a time: give their pages back
        return self.loaded[name]

    def write_table(self, key: str) -> None:
        """Render table ``key`` from the results so far (``report.insertion_tables``; verify renders it again)."""
        text = self.render.tables[key](self.rep.results, self.out)
        write_text(self.out / f"{key}.md", text)
        self.rep.tables[key] = text

    # ---------------------------------------------------------------- steps
    def scan(self) -> None:
        p = self.p
        sim = make_simulator(p.engine, noise_sigma=p.noise_sigma)
        self.progress("boundary scan", 0, 1)
        result = scan_development(p, sim)
        self.rep.add_calls(sim.engine_calls)
        write_with(self.out / "scan.parquet", result.scans.to_parquet)
        summary = result.summary()
        summary["frozen_delta"] = p.delta
        self.rep.results["scan"] = summary
        first = str(result.scans["instance_id"].iloc[0])
        # The readings of the instance the section draws (verify draws Fig. 4a again from them and scan.parquet).
        grid = result.grid[result.grid["instance_id"] == first].reset_index(drop=True)
        write_with(self.out / SCAN_GRID, grid.to_parquet)
        self.rep.figures["scan"] = str(self.render.scan_figure(grid, result.scans, first, summary["delta"], self.out / "fig_4a_teaser_scan_section.png"))
        self.write_table("scan")

    def cover_search(self, limit: int | None) -> None:
        p = self.p
        cfg = p.run_config("cover-search", "development", "development", "cover")
        sim = build_simulator(cfg)
        table = search_cover_schedule(cfg, sim, limit=limit, progress=lambda d, t: self.progress("cover search", d, t))
        self.rep.add_calls(sim.engine_calls)
        write_with(self.out / "cover_search.parquet", table.assign(schedule=table["schedule"].map(str)).to_parquet)
        best = table.iloc[0]
        self.rep.results["cover"] = {
            "winner": [float(u) for u in best["schedule"]], "winner_failure": float(best["failure"]),
            "frozen": list(p.cover_schedule), "candidates": int(len(table)),
            "frozen_rank": int(table.index[table["schedule"].map(lambda s: list(map(float, s)) == list(p.cover_schedule))][0]) + 1
            if any(table["schedule"].map(lambda s: list(map(float, s)) == list(p.cover_schedule))) else None,
        }
        self.write_table("cover_search")

    def rollouts(self) -> None:
        p = self.p
        both = ("blind_robust", "probe_robust")
        self.run("dev_random", p.run_config("dev_random", "development", "development", "random"))
        self.run("A_cover", p.run_config("A_cover", "A", "A", "cover", methods=("blind_bayes", "probe_robust")))
        for part in ("cal", "test"):
            self.run(f"B_{part}_cover", p.run_config(f"B_{part}_cover", "B", f"B_{part}_cover", "cover", methods=both))
            self.run(f"B_{part}_random", p.run_config(f"B_{part}_random", "B", f"B_{part}_random", "random"))
        f = p.faults
        common = dict(boundary="corrected", seed_offset=f.seed_offset)
        self.run("faults_base", p.run_config("faults_base", "B", "B_test_random", "random", **common))
        self.run("faults_noise", p.run_config("faults_noise", "B", "B_test_random", "random", noise_factor=f.noise_factor, **common))
        self.run("faults_prior", p.run_config("faults_prior", "B", "B_test_random", "random", truth_half_width=f.prior_half_width, **common))
        # Test C: drawn from its own seed stream after the correction froze.
        self.run("C_cover", p.run_config("C_cover", "C", "C_cover", "cover"))
        self.run("C_random", p.run_config("C_random", "C", "C_random", "random"))
        # The 192-instance pool of the re-split study (cover schedule).
        pool = p.instances["B"].count * 2
        cfg = p.run_config("B_pool_cover", "B", "B_pool_cover", "cover")
        cfg = cfg.model_copy(update={"instances": cfg.instances.model_copy(update={"count": pool})})
        self.run("B_pool_cover", cfg)
        corrected = {"model": {"boundary": "corrected", "delta": p.delta}}
        for name in ("C_cover", "C_random", "B_cal_cover"):
            self.replay(name, f"{name}_corrected", corrected)

    def table_insertion(self) -> None:
        L, b = self.loaded, self.boot
        a = L["A_cover"].episodes
        blind_a = a[(a.method == "blind_bayes") & (a.status == "ok")]
        a_no = cluster_bootstrap_mean(blind_a["realized"].to_numpy(float), blind_a["instance_id"].to_numpy(), **b)
        a_k5 = episode_metrics(a, 5, **b)["failure"]
        # Table II's insertion row: Blind-Bayes minus cover k = 5, paired on (instance, repeat).
        cover_a = a[(a.method == "probe_robust") & (a.k == 5) & (a.status == "ok")]
        a_paired = paired_bootstrap(cover_a, blind_a, "realized", keys=("instance_id", "repeat"), **b)
        self.cal_cover = calibrate(L["B_cal_cover"], L["B_test_cover"], alpha=self.p.alpha, budgets=[1, 2, 3, 4, 5], **b,
                                   **self.chunk, record=self.commits["cover"])
        self.cal_random = calibrate(L["B_cal_random"], L["B_test_random"], alpha=self.p.alpha, budgets=[1, 2, 3, 5, 8],
                                    **b, **self.chunk, record=self.commits["random"])
        res = {
            "A.no_probe": [a_no.estimate, a_no.lo, a_no.hi],
            "A.cover_k5": a_k5,
            "A.paired_reduction_k5": [a_paired.difference.estimate, a_paired.difference.lo, a_paired.difference.hi],
            "B.cost_table": self.cal_cover.cost.to_dict("records"),
            "B.cost_differences": self.cal_cover.cost_differences.to_dict("records"),
            "margin_cover": self.cal_cover.margin.gamma,
            "margin_random": self.cal_random.margin.gamma,
            "distribution_free_margin_cover": self.cal_cover.distribution_free_margin,
            "thresholds_cover": {int(k): float(v) for k, v in self.cal_cover.thresholds.items()},
            "thresholds_random": {int(k): float(v) for k, v in self.cal_random.thresholds.items()},
            "simultaneous_cover": float(self.cal_cover.simultaneous_threshold),
            "simultaneous_random": float(self.cal_random.simultaneous_threshold),
        }
        self.rep.results["table_insertion"] = res
        self.write_table("table_IV_insertion")

    def table_audit(self) -> None:
        t3 = self.cal_random.table3
        self.rep.results["table_audit"] = {"table": t3.to_dict("records"), "summary": self.cal_random.summary}
        test = self.loaded["B_test_random"].episodes
        esc = {k: episode_metrics(test, k, **self.boot) for k in (1, 8)}
        self.rep.results["text"] = {"escape_k1": esc[1]["escape"], "escape_k8": esc[8]["escape"],
                                     "episode_coverage_k1": esc[1]["episode_coverage"], "episode_coverage_k8": esc[8]["episode_coverage"]}
        self.write_table("table_III_audit")

    def table_testc(self) -> None:
        L, b = self.loaded, self.boot
        old_r, new_r = L["C_random"].episodes, L["C_random_corrected"].episodes
        old_c, new_c = L["C_cover"].episodes, L["C_cover_corrected"].episodes
        res = {}
        spec = [("escape_random_k8", old_r, new_r, 8, "escaped"), ("episode_coverage_random_k8", old_r, new_r, 8, "covered"),
                ("optimism_random_k8", old_r, new_r, 8, "optimism"), ("failure_random_k8", old_r, new_r, 8, "realized"),
                ("failure_cover_k5", old_c, new_c, 5, "realized"), ("failure_cover_k1", old_c, new_c, 1, "realized")]
        for key, old, new, k, col in spec:
            mo, mn = episode_metrics(old, k, **b), episode_metrics(new, k, **b)
            name = {"escaped": "escape", "covered": "episode_coverage", "realized": "failure", "optimism": "optimism"}[col]
            d = paired(new, old, k, col, **b)  # old - corrected
            res[key] = {"old": mo[name], "corrected": mn[name], "old_minus_corrected": d}
        cal_old = calibrate(L["B_cal_cover"], L["C_cover"], alpha=self.p.alpha, budgets=[1, 2, 3, 4, 5], **b, **self.chunk,
                            record=self.commits["testc_old"])
        cal_new = calibrate(L["B_cal_cover_corrected"], L["C_cover_corrected"], alpha=self.p.alpha, budgets=[1, 2, 3, 4, 5],
                            **b, **self.chunk, record=self.commits["testc_corrected"])
        fo, fn = setmargin_failure(cal_old), setmargin_failure(cal_new)
        res["failure_cover_k5_setcal_margin"] = {"old": fo, "corrected": fn,
                                                 "old_minus_corrected": setmargin_paired(cal_old, cal_new, **b),
                                                 "simultaneous_threshold": {"old": cal_old.simultaneous_threshold, "corrected": cal_new.simultaneous_threshold}}
        self.rep.results["table_testc"] = res
        self.write_table("table_V_testc")


    def faults(self) -> None:
        p, L, b = self.p, self.loaded, self.boot
        f = p.faults
        arms = fault_arms(f.noise_factor, f.prior_half_width, f.particles, f.frame_offset, f.temperature, p.sigma)
        rollouts = {"base": L["faults_base"], "noise": L["faults_noise"], "prior": L["faults_prior"]}
        episodes = run_fault_harness(rollouts, arms, progress=lambda d, t: self.progress("fault harness", d, t), **self.chunk)
        store_episodes(episodes, self.out / "faults_episodes.parquet", extra=("fault", "arm"))
        kmax = p.budgets["random"]
        res = {}
        for fault in FAULTS:
            fa = episodes[(episodes.fault == fault) & (episodes.arm == "fault")]
            row = {"fail": episode_metrics(fa, kmax, **b)["failure"]}
            probe = probe_rows(fa)
            if probe[probe.k == kmax]["escaped"].any():
                auc = surprise_auc(probe, final_k=kmax, **b)
                row["surprise_auc"] = float(auc[auc.k == kmax]["auc"].iloc[0]) if "auc" in auc.columns else None
            for arm in ("tempered", "fix"):
                other = episodes[(episodes.fault == fault) & (episodes.arm == arm)]
                if len(other):
                    row[arm] = episode_metrics(other, kmax, **b)["failure"]
            fix = episodes[(episodes.fault == fault) & (episodes.arm == "fix")]
            if len(fix):
                row["paired_fix"] = paired(fa, fix, kmax, "realized", **b)
            res[fault] = row
        signatures = signature_table(episodes)
        write_with(self.out / "fault_signatures.parquet", signatures.to_parquet)
        self.rep.results["fault_signatures"] = signature_points(signatures)
        self.rep.figures["signatures"] = str(self.render.fault_signatures(signatures, self.out / "fig_7_signatures.png",
                                                                          n=signature_n(episodes, kmax)))
        self.rep.results["table_faults"] = res
        self.write_table("table_VIII_faults")

    def robust(self) -> None:
        p, L, b = self.p, self.loaded, self.boot
        r = p.robust
        cands = robust_candidates(r.temperatures, r.epsilons, r.rejuvenation, r.mixture_range)
        record: list[pd.DataFrame] = []
        tuning = tune_robust_filters(L["dev_random"], cands, progress=lambda d, t: self.progress("robust tuning", d, t),
                                     record=record, **self.chunk)
        chosen = {row.family: (row.value, row.belief) for row in tuning[tuning.chosen].itertuples()}
        base = L["faults_base"]
        kmax = p.budgets["random"]
        arms = {"deployed": replay_episodes(base, {"model": {"boundary": "deployed"}}, **self.chunk)[0]}
        for family, (value, belief) in chosen.items():
            arms[family] = replay_episodes(base, {"model": {"boundary": "deployed"}, "belief": belief}, **self.chunk)[0]
        if "mixture" in chosen:
            arms["base"] = base.episodes
            arms["mixture_right"] = replay_episodes(base, {"belief": chosen["mixture"][1]}, **self.chunk)[0]
        tuning = tuning.drop(columns="belief")
        self.rep.results["robust"] = robust_summary(tuning, arms, kmax, b)
        stored = [part.assign(part="tuning") for part in record]
        stored += [probe_rows(episodes, kmax).assign(part=name) for name, episodes in arms.items()]
        table = pd.concat(stored, ignore_index=True)[["part", "family", "value", *ROBUST_COLUMNS]]
        write_with(self.out / ROBUST_FILE, lambda buf: table.to_parquet(buf, compression="zstd", index=False))
        self.write_table("robust")

    def resplits(self) -> None:
        p = self.p
        pool = self.loaded["B_pool_cover"]
        count = p.resplits["count"]
        # The re-split study calibrates the cover schedule's last budget only.
        table = resplit_table(pool, p.alpha, count, p.resplits["seed"], 5, p.bootstrap.seed,
                              lambda n: self.progress("re-splits", n, count))
        write_with(self.out / "resplits.parquet", table.to_parquet)
        summary = {"level_mean_sd": [float(table.level.mean()), float(table.level.std(ddof=1))],
                   "failure_mean_sd": [float(table.failure.mean()), float(table.failure.std(ddof=1))],
                   "heldout_cluster_coverage": float(table.heldout_cluster_coverage.mean()),
                   "margin_optimistic_fraction": float(table.margin_optimistic.mean()),
                   "splits": count, "pool": int(len(pool.instances))}
        self.rep.results["resplits"] = summary
        self.write_table("resplits")

    def commit_gates(self) -> None:
        """Commit gates on Split B, cover schedule (paper Fig. "commit decision" b, c)."""
        from probecommit.runner.calibration import gates

        L = self.loaded
        result = gates(L["B_cal_cover"], L["B_test_cover"], alpha=self.p.alpha, **self.boot, **self.chunk,
                       record=self.commits["gates"])
        k = self.p.budgets["random"]
        coverage = coverage_vs_nominal(L["B_cal_random"].episodes, L["B_test_random"].episodes, k)
        write_with(self.out / "coverage_vs_nominal.parquet", coverage.to_parquet)
        path = self.render.decision_figure(coverage, result, self.out / "fig_6_decision.png")
        self.rep.figures["commit_gates"] = str(path)
        summary = result.summary
        self.rep.results["gates"] = {"summary": summary.to_dict("records"), "info": gates_info(result.info)}
        write_with(self.out / "gates_curves.parquet", result.curves.to_parquet)
        self.write_table("gates")

    def setup_table(self) -> None:
        """Table I, the insertion row, from the protocol."""
        p = self.p
        self.write_table("table_I_setup_insertion")

    def decisive_tap(self) -> None:
        """Fig. (teaser b): a development episode where a chamfer-band tap removes the truth."""
        dev = self.loaded["dev_random"]
        p = self.p
        trace_old, model_old, _ = trace_for_run(dev)
        cfg_new = with_model(dev.config, boundary="corrected", delta=p.delta)
        trace_new, model_new, _ = trace_for_run(dev, cfg_new)
        batch = trace_old.batch
        for k in trace_old.budgets:
            prev = trace_old.states[k - 1] if k - 1 in trace_old.states else None
            now = trace_old.states[k]
            z_true = batch.truths[:, 0]
            z = now.particles[..., 0]
            escaped = (z_true < z.min(axis=1)) | (z_true > z.max(axis=1))
            kept_new = trace_new.states[k].particles[..., 0]
            ok_new = (z_true >= kept_new.min(axis=1)) & (z_true <= kept_new.max(axis=1))
            if prev is not None:
                zp = prev.particles[..., 0]
                was_in = (z_true >= zp.min(axis=1)) & (z_true <= zp.max(axis=1))
            else:
                was_in = np.ones_like(escaped)
            hits = np.flatnonzero(escaped & was_in & ok_new)
            if len(hits):
                e = int(hits[0])
                series = decisive_tap_series(z[e], now.weights[e], kept_new[e], trace_new.states[k].weights[e],
                                             float(z_true[e]), float(np.ravel(batch.u[e, k - 1])[0]),
                                             float(np.ravel(batch.y[e, k - 1])[0]), k)
                write_with(self.out / DECISIVE_TAP, lambda buf: series.to_parquet(buf, compression="zstd", index=False))
                path = self.render.decisive_tap_figure(series, self.out / "fig_4b_teaser_decisive_tap.png")
                self.rep.figures["decisive_tap"] = str(path)
                return

    def store_episodes(self) -> None:
        """The episode tables verify recomputes the summary numbers from, compactly, in one file."""
        frames = [self.loaded[name].episodes.assign(run=name) for name in RECOMPUTED_RUNS if name in self.loaded]
        store_episodes(pd.concat(frames, ignore_index=True), self.out / "episodes.parquet", extra=("run",))
        store_commits(self.commits, self.out / COMMITS_FILE)

    # ---------------------------------------------------------------- all
    def run_all(self, cover_limit: int | None = None) -> Reproduction:
        start = time.perf_counter()
        steps = [self.scan, lambda: self.cover_search(cover_limit), self.rollouts, self.table_insertion,
                 self.table_audit, self.table_testc, self.faults, self.robust, self.resplits, self.commit_gates,
                 self.setup_table, self.decisive_tap]
        for step in steps:
            step()
            release_free_heap()  # the next step's peak starts from what is live, not this one's high-water mark
        self.store_episodes()
        self.rep.wall_s = time.perf_counter() - start
        payload = {"results": self.rep.results, "engine_calls": self.rep.engine_calls, "wall_s": self.rep.wall_s,
                   "figures": self.rep.figures}
        write_text(self.out / "results.json", json.dumps(payload, indent=2, default=_json_default))
        return self.rep


def gates_info(info: dict[str, Any]) -> dict[str, Any]:
    """The gates' ``info`` as published: the surprise AUC table (one row per budget) as records, an AUC the
    data leave undefined (no escape at a budget) ``None`` (a DataFrame used to reach results.json as ``{}``)."""
    table = info["surprise"]
    records = [{k: (None if isinstance(v, float) and v != v else v) for k, v in row.items()}
               for row in table.to_dict("records")]
    return {**info, "surprise": records}


def _json_default(o: Any) -> Any:
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.bool_,)):
        return bool(o)
    if isinstance(o, (np.ndarray,)):
        return o.tolist()
    if hasattr(o, "__dict__"):
        return {k: v for k, v in o.__dict__.items() if not k.startswith("_")}
    return str(o)


def reproduce_insertion(root: str | Path, render: Render, quick: bool = False,
                        protocol_path: str | Path = DEFAULT_PROTOCOL, progress: Progress = no_progress,
                        workers: int = 1) -> Reproduction:
    """Run the whole MuJoCo insertion reproduction into ``root``, drawing with ``render``."""
    protocol = load_protocol(protocol_path)
    if quick:
        protocol = protocol.quick_version()
    repro = InsertionReproduction(protocol, Path(root), render, progress, workers)
    return repro.run_all(cover_limit=protocol.quick.cover_subsets if quick else None)
