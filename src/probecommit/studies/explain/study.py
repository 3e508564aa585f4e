"""``probecommit reproduce explain``: the measurements behind every difference from the paper.

Reads the run directories of ``reproduce insertion`` and ``reproduce engines`` (and the GRU's
results when present) under the same root, adds a few controlled runs (:mod:`.runs`), and
writes ``results.json``: ``{"results": {group: {name: value}}}`` with values numbers or
``[point, lo, hi]`` cluster-bootstrap triples. ``EXPLAIN_KEYS.md`` at the repository root says
what each key measures.
"""

from __future__ import annotations

import functools
import json
import re
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd
import yaml

from probecommit.audit.stats import paired_bootstrap
from probecommit.process.memory import large_arrays_apart, release_free_heap
from probecommit.runner.replay import load_run
from probecommit.studies.explain.replay_final import replay_at
from probecommit.studies.explain import (calibration_rows, draw_audit, draw_faults, engines_x, generator, more, resplits,
                                         robust_rows, runs, stored, surprise_variants)
from probecommit.studies.explain.shared_beliefs import SharedBeliefs, cyclic_pairs
from probecommit.studies.explain.background import Background
from probecommit.studies.explain import pieces
from probecommit.studies.explain.lanes import ReadDict, Reads
from probecommit.studies.explain import timing
from probecommit.studies.explain.timing import StepClock
from probecommit.studies.explain import ex4, ex5_calibration, ex6, ex7, ex8, ex9_calibration, ex10
from probecommit.studies.explain import ex11
from probecommit.studies.explain import ex13
from probecommit.studies.explain import ex14
from probecommit.studies.explain import ex16
from probecommit.studies.explain import ex17
from probecommit.studies.explain import ex19
from probecommit.studies.explain import ex22
from probecommit.studies.explain import ex20
from probecommit.studies.explain import ex23
from probecommit.studies.explain import ex21
from probecommit.studies.explain import ex24
from probecommit.studies.explain import ex25
from probecommit.studies.explain import ex27
from probecommit.studies.explain import ex32
from probecommit.studies.explain import ex12_distinct, ex12_simultaneous
from probecommit.studies.explain import ex15_readings, ex15_union
from probecommit.studies.explain import ex18_grasp, ex18_share
from probecommit.studies.explain import ex26_grasp
from probecommit.studies.explain import ex28_plateau
from probecommit.studies.explain import ex30_fresh
from probecommit.studies.explain import ex33_aim
from probecommit.studies.explain import ex31_shift
from probecommit.studies.explain import ex34_fixed
from probecommit.studies.explain import ex43_setonly
from probecommit.studies.explain import ex35_pools
from probecommit.studies.explain import ex36_coverage, ex36_testc
from probecommit.studies.explain import ex37_adjusted, ex37_filters
from probecommit.studies.explain import ex38_physx
from probecommit.studies.explain import ex39_pybullet
from probecommit.studies.explain import ex40_solver
from probecommit.studies.explain import ex41_slop
from probecommit.studies.explain import ex29_band
from probecommit.studies.explain import gru as gru_study
from probecommit.studies.explain.margin import margin_curve
from probecommit.studies.paper_values import PRINTED
from probecommit.studies.protocol import Protocol, load_protocol
from probecommit.store.safefile import write_text, write_with

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "paper" / "explain.yaml"
Progress = Callable[[str, int, int], None]
#: The paper's frozen cover schedule (mm), as printed.
COVER_SCHEDULE = [float(u) for u in PRINTED["T07-cover-schedule.schedule"].strip("[]").split(",")]
#: The cost-of-calibration comparisons (baseline, treatment) and their key names.
COST_LABELS = {("no calibration", "set calibration + margin"): "full", ("no calibration", "set calibration"): "set",
               ("set calibration", "set calibration + margin"): "margin"}


def cost_keys(differences: list[dict[str, Any]]) -> dict[str, list[float]]:
    """``missing.cost_of_calibration.*`` from the insertion study's Table IV paired differences (records; verify
    passes the ones it recomputed)."""
    return {f"cost_of_calibration.{COST_LABELS[(row['baseline'], row['treatment'])]}": [row["difference"], row["lo"], row["hi"]]
            for row in differences}


def surprise_variant_keys(rows: pd.DataFrame, schedules: pd.DataFrame, k: int, boot: dict[str, int]) -> dict[str, Any]:
    """``missing.surprise_variants.*`` from the stored surprise readings and the stored schedule rows (labels)."""
    out: dict[str, Any] = {}
    for label, run in (("ours", "ours_B_test"), ("paper_schedule", "paper_B_test")):
        aucs = surprise_variants.aucs_from_table(rows[rows["schedule"] == label].reset_index(drop=True),
                                                 schedules[schedules["run"] == run], [1, k], k,
                                                 resamples=int(boot["resamples"]), seed=int(boot["seed"]))
        out.update({f"surprise_variants.{label}.{key}": v for key, v in aucs.items()})
    return out


def load_explain_config(path: str | Path | None = None) -> dict[str, Any]:
    return yaml.safe_load(Path(path or CONFIG).read_text())


def _probe(episodes: pd.DataFrame, k: int | None = None) -> pd.DataFrame:
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    return rows if k is None else rows[rows["k"] == k]


def _triple(iv: Any) -> list[float]:
    return [float(iv.estimate), float(iv.lo), float(iv.hi)]


def _final_escape(episodes: pd.DataFrame, k: int) -> pd.Series:
    last = _probe(episodes, k)
    return last.set_index(["instance_id", "repeat"])["escaped"].astype(bool)


class Explain:
    """One explain reproduction: where the runs are, the settings, and the results as they fill in."""

    def __init__(self, root: Path, quick: bool, progress: Progress, workers: int, config: dict[str, Any],
                 ready: Callable[..., None] | None = None) -> None:
        protocol = load_protocol()
        self.p: Protocol = protocol.quick_version() if quick else protocol
        self.quick = quick
        self.root = Path(root)
        self.ins = self.root / "insertion" / "runs"
        self.runs = self.root / "explain" / "runs"
        self.progress = StepClock(progress)  # each step's wall and CPU seconds logged (``-v``)
        self.workers = workers
        self.cfg = config
        #: ``ready(names)`` returns once those targets (None: the engines, GRU, breadth and cost studies)
        #: are done: side by side (``report.schedule.LATE_NEEDS``) this target starts before them. None:
        #: they are done.
        self.ready = ready
        self.boot = dict(resamples=self.p.bootstrap.resamples, seed=self.p.bootstrap.seed)
        #: What the main lane read, by step: no later step may read what a step set aside fills (``lanes``).
        self.reads = Reads()
        self.res: dict[str, dict[str, Any]] = {g: ReadDict(self.reads, "res", g) for g in (
            "missing", "committed_pool", "instance_generator", "margin_per_gamma", "thresholds", "gru", "physx_capture",
            "boundary_fault", "robust", *more.GROUPS,
            "ex5_calibration", *ex4.GROUPS, *ex6.GROUPS, *ex7.GROUPS,
            *ex8.GROUPS, "ex9_calibration", *ex10.GROUPS,
            *ex11.GROUPS, *ex13.GROUPS,
            *ex14.GROUPS,
            *ex16.GROUPS,
            *ex17.GROUPS,
            *ex19.GROUPS,
            *ex22.GROUPS,
            *ex20.GROUPS,
            *ex23.GROUPS,
            *ex31_shift.GROUPS,
            *ex34_fixed.GROUPS,
            *ex43_setonly.GROUPS,
            *ex21.GROUPS,
            *ex24.GROUPS,
            *ex25.GROUPS,
            *ex27.GROUPS,
            *ex32.GROUPS,
            ex12_distinct.GROUP, ex12_simultaneous.GROUP,
            ex15_readings.GROUP, ex15_union.GROUP,
            ex18_share.GROUP, ex18_grasp.GROUP, ex26_grasp.GROUP, ex28_plateau.GROUP, ex30_fresh.GROUP,
            ex29_band.GROUP, ex33_aim.GROUP, ex35_pools.GROUP, *ex36_testc.GROUPS, ex36_coverage.GROUP,
            ex37_adjusted.GROUP, ex37_filters.GROUP, ex38_physx.GROUP, ex39_pybullet.GROUP,
            ex40_solver.GROUP, ex41_slop.GROUP)}
        self.tables: dict[str, pd.DataFrame] = ReadDict(self.reads, "tables")
        #: Stored rows written beside results.json as they are, by file name (``more``'s steps).
        self.stored: dict[str, pd.DataFrame] = ReadDict(self.reads, "stored")
        #: Re-executed commits by calibration (``Recorder``) and episodes of the step's own runs by run name, that
        #: verify recomputes the gates, calibration and thresholds from (``calibration_rows.COMMITS``, ``EPISODES``).
        self.commits: dict[str, list[pd.DataFrame]] = {}
        self.episodes: dict[str, pd.DataFrame] = {}
        self._loaded: dict[str, Any] = {}
        #: Steps run in a process of their own beside the later steps, by result group (``background``).
        self.background = Background()
        #: Keys merged from jobs aside so far, by group (``_merge``).
        self._merged: dict[str, int] = {}

    def load(self, name: str) -> Any:
        if name not in self._loaded:
            self._loaded[name] = load_run(self.ins / name)
        return self._loaded[name]

    def insertion_results(self) -> dict[str, Any]:
        """The insertion study's ``results.json`` (read once; several steps read it)."""
        if "insertion_results" not in self._loaded:
            path = self.root / "insertion" / "results" / "results.json"
            self._loaded["insertion_results"] = json.loads(path.read_text())["results"]
        return self._loaded["insertion_results"]

    def fault_episodes(self) -> pd.DataFrame:
        """The fault harness's episode table (read once; several steps read it)."""
        if "faults_episodes" not in self._loaded:
            self._loaded["faults_episodes"] = pd.read_parquet(self.root / "insertion" / "results" / "faults_episodes.parquet")
        return self._loaded["faults_episodes"]

    # ------------------------------------------------------------------ part 3: missing items
    def missing(self) -> None:
        self._random_gates()
        self._corrected_thresholds()
        self._cost_and_testc()

    def _random_gates(self) -> None:
        """Every commit gate under random probes (the paper reports only that posterior variance is lowest);
        the re-executed rows are kept (``commits.parquet``) for verify's ``gates_from_commits``."""
        from probecommit.runner.calibration import gates

        self.progress("explain: random-probe gates", 0, 1)
        self.commits["gates_random"] = []
        result = gates(self.load("B_cal_random"), self.load("B_test_random"), alpha=self.p.alpha, **self.boot,
                       chunk_instances=48, record=self.commits["gates_random"])
        self.tables["random_gates_record"] = list(self.commits["gates_random"])  # ex6's E63: one range for all gates
        for group, values in calibration_rows.random_gate_keys(result).items():
            self.res[group].update(values)

    def _corrected_thresholds(self) -> None:
        """The corrected random-probe simultaneous threshold, and two stored thresholds recomputed
        (``calibration_rows.threshold_keys``; the corrected replay's episodes are stored)."""
        self.progress("explain: corrected random calibration", 0, 1)
        corrected = runs.corrected_replay(self.ins / "B_cal_random", self.runs, self.p.delta)
        self.episodes[calibration_rows.RANDOM_CORRECTED] = corrected.episodes
        names = ("B_cal_random", "B_cal_cover_corrected")
        keys = calibration_rows.threshold_keys({calibration_rows.RANDOM_CORRECTED: corrected.episodes,
                                                **{n: self.load(n).episodes for n in names}},
                                               self.cfg["random_budgets"], list(range(1, self.p.budgets["cover"] + 1)),
                                               self.p.alpha)
        for group, values in keys.items():
            self.res[group].update(values)

    def _cost_and_testc(self) -> None:
        """The cost-of-calibration differences as keys (Test C's final escapes are ``stored.harness_keys``')."""
        self.res["missing"].update(cost_keys(self.insertion_results()["table_insertion"]["B.cost_differences"]))

    def physx_coverage(self) -> None:
        """Cluster and episode coverage of our PhysX runs at the final random budget."""
        engines = self.root / "engines" / "runs"
        paths = {variant: engines / f"sapien_B_test_random{suffix}"
                 for variant, suffix in (("deployed", ""), ("mj_offset", "_mj_offset"), ("own_scan", "_own_scan"))}
        frames = [load_run(path).episodes.assign(variant=v) for v, path in paths.items() if path.is_dir()]
        if frames:
            self.res["missing"].update(stored.physx_coverage_keys(pd.concat(frames, ignore_index=True),
                                                                  self.p.budgets["random"]))

    # ------------------------------------------------------------------ committed pool
    def committed_pool(self, paper_schedule: dict[str, Any]) -> None:
        """The raw gate's pool under each escape definition, per schedule; then the schedules' failures."""
        k = self.p.budgets["cover"]
        runs = {"ours_B_test": self.load("B_test_cover"), "paper_B_test": paper_schedule["test"],
                "random_B_test": self.load("B_test_random"), "ours_A": self.load("A_cover"), "paper_A": paper_schedule["A"]}
        self.tables["schedules"] = stored.schedule_table({n: _probe(r.episodes) for n, r in runs.items()}, k)
        for group, values in stored.pool_keys(self.tables["schedules"], self.boot).items():  # what verify recomputes
            self.res[group].update(values)
        self._surprise_variants(paper_schedule["test"], k)
        self._schedule_failure(paper_schedule)

    def _surprise_variants(self, paper_test: Any, k: int) -> None:
        """The surprise AUC with the paper's words read as a class probability, and with escape read as
        "outside the retained set", on both schedules (k = 1 and the final budget)."""
        self.progress("explain: surprise read as a class probability", 0, 1)
        rows = [surprise_variants.variant_table(run, label)
                for label, run in (("ours", self.load("B_test_cover")), ("paper_schedule", paper_test))]
        self.stored[surprise_variants.STORED] = pd.concat(rows, ignore_index=True)
        self.res["missing"].update(surprise_variant_keys(self.stored[surprise_variants.STORED], self.tables["schedules"], k,
                                                         self.boot))

    def _schedule_failure(self, paper_schedule: dict[str, Any]) -> None:
        """Table IV's calibrated rows and the cost of calibration under the paper's schedule (the schedules'
        failures on the same instances are ``stored.pool_keys``'); the re-executed rows and both runs'
        episodes are kept for verify's ``calibration_from_tables``."""
        from probecommit.runner.calibration import calibrate

        k = self.p.budgets["cover"]
        self.progress("explain: calibration under the paper's schedule", 0, 1)
        self.commits["paper_schedule"] = []
        cal = calibrate(paper_schedule["cal"], paper_schedule["test"], alpha=self.p.alpha, budgets=list(range(1, k + 1)),
                        **self.boot, chunk_instances=48, record=self.commits["paper_schedule"])
        self.episodes[calibration_rows.PAPER_CAL] = paper_schedule["cal"].episodes
        self.episodes[calibration_rows.PAPER_TEST] = paper_schedule["test"].episodes
        for group, values in calibration_rows.paper_calibration_keys(cal).items():
            self.res[group].update(values)

    def resplits_paper_schedule(self) -> None:
        """The 50 re-splits of the 192-instance cover pool under the paper's schedule (``resplits``)."""
        self.progress("explain: re-splits under the paper's schedule", 0, 1)
        self.stored[resplits.STORED] = resplits.run(self.p, COVER_SCHEDULE, self.runs, self.workers)
        out = resplits.summary(self.stored[resplits.STORED])  # what verify recomputes from the stored rows
        self.res["committed_pool"].update({f"resplits.paper_schedule.{k}": v for k, v in out.items()})

    # ------------------------------------------------------------------ margin and thresholds
    def margins(self, paper_schedule: dict[str, Any]) -> None:
        """The margin curve of both schedules (every gamma committed), and the margins, thresholds, their
        intervals and strata: ``calibration_rows.margin_rule_keys`` of the per-instance rows stored beside
        the curve (what verify recomputes)."""
        g, p = self.res["margin_per_gamma"], self.p
        k = p.budgets["cover"]
        budgets = list(range(1, k + 1))
        instances, sums = [], []
        for label, run in (("ours", self.load("B_cal_cover")), ("paper_schedule", paper_schedule["cal"])):
            self.progress(f"explain: margin curve ({label})", 0, 1)
            escaped = _final_escape(run.episodes, k)
            curve = margin_curve(run, budgets, p.alpha, escaped)
            self.tables[f"margin_{label}"] = curve["table"].assign(schedule=label)
            g.update(stored.margin_keys(self.tables[f"margin_{label}"]))  # what verify recomputes from the stored curve
            instances.append(calibration_rows.instance_table(label, curve, escaped))
            sums.append(calibration_rows.sums_table(label, curve))
            if label == "ours":
                nu_curve = margin_curve(run, budgets, p.alpha, None, set_calibrated=False)
                self.tables[f"margin_{calibration_rows.NU_EXECUTOR}"] = nu_curve["table"].assign(
                    schedule=calibration_rows.NU_EXECUTOR)
        self.tables["calibration_instances"] = pd.concat(instances, ignore_index=True)
        self.tables["calibration_sums"] = pd.concat(sums, ignore_index=True)
        curves = pd.concat([t for name, t in self.tables.items() if name.startswith("margin_")], ignore_index=True)
        keys = calibration_rows.margin_rule_keys(curves, self.tables["calibration_instances"], self.tables["calibration_sums"],
                                                 alpha=p.alpha, edge=self.cfg["stratum_edge_mm"], boot=self.boot)
        for group, values in keys.items():
            self.res[group].update(values)

    # ------------------------------------------------------------------ instance draws
    def instance_generator(self) -> None:
        """Each uniform run's frozen draw against redraws of its generator, from the stored draws (``generator``)."""
        edge, seeds = self.cfg["stratum_edge_mm"], self.cfg["generator_seeds_quick" if self.quick else "generator_seeds"]
        frozen = {}
        for name in ("A_cover", "B_cal_cover", "B_test_cover", "B_cal_random", "B_test_random", "C_cover", "C_random"):
            run = self.load(name)
            cfg = run.config.instances
            if cfg.sampling == "uniform":
                frozen[name] = (run.instances, cfg.split, cfg.seed)
        if not frozen:
            return
        self.stored[generator.STORED] = generator.generator_table(frozen, seeds)
        self.res["instance_generator"].update(generator.generator_keys(self.stored[generator.STORED], edge))

    def draw_runs(self) -> list[tuple[str, Any, Any]]:
        """The fresh draws of the generator and their corrected replays (``runs.fresh_draws``; finished ones resume)."""
        count = self.cfg["fresh_draws_quick" if self.quick else "fresh_draws"]
        self.progress("explain: fresh draws of the generator", 0, 1)
        return runs.fresh_draws(self.p, self.runs, count, self.workers)

    def draws(self) -> None:
        """Escape, failure and the boundary fix across fresh draws of the generator (analytic scene)."""
        out, p, b = self.res["instance_generator"], self.p, self.boot
        kmax, edge = p.budgets["random"], self.cfg["stratum_edge_mm"]
        rows = []
        drawn = self.draw_runs()
        for split, deployed, corrected in drawn:
            old, new = _probe(deployed.episodes), _probe(corrected.episodes)
            x = deployed.instances["true_x_hole"].to_numpy(float)
            fix = paired_bootstrap(old[old["k"] == kmax], new[new["k"] == kmax], "realized", resamples=2, seed=0)
            rows.append({"split": split, "share_beyond": generator.share_beyond(x, edge),
                         "escape_k1": float(old[old["k"] == 1]["escaped"].mean()),
                         "escape_k8": float(old[old["k"] == kmax]["escaped"].mean()),
                         "failure_k8": float(old[old["k"] == kmax]["realized"].mean()),
                         "optimism_k8": float((old[old["k"] == kmax]["realized"] - old[old["k"] == kmax]["predicted"]).mean()),
                         "paired_fix_k8": float(fix.difference.estimate)})
        cells: dict[str, list[dict[str, float]]] = {}
        self._draw_audit(drawn, cells)
        self._draw_faults(drawn, cells)
        table = pd.DataFrame(rows)
        mujoco = _probe(self.load("B_test_random").episodes, kmax)
        out.update(stored.draws_keys(table))  # the summaries verify recomputes from the stored rows
        out.update(generator.analytic_equals_mujoco(table, mujoco))
        self.tables["draws"] = table.assign(schedule="draws")
        first = {"audit": 0, "faults": 0, "audit_fresh_cal": 1, "gates_fresh_cal": 1}
        self.tables["cells"] = stored.cells_table(cells, first)
        out.update(stored.cells_keys(self.tables["cells"]))

    def _draw_audit(self, drawn: list[tuple[str, Any, Any]], parts: dict[str, list[dict[str, float]]]) -> None:
        """Table III's cells on each fresh draw under the frozen Split B calibration (t_k and gamma of our
        calibration run): the range over draws that a paper cell is compared with (``draw_audit``)."""
        res = self.insertion_results()
        thresholds = {int(r["k"]): float(r["threshold"]) for r in res["table_audit"]["table"]}
        gamma = float(res["table_insertion"]["margin_random"])
        budgets, nominal = sorted(thresholds), 1 - self.p.alpha
        every = list(range(1, self.p.budgets["random"] + 1))  # the gates' budgets: every one the draws commit at
        # each draw's beliefs once, for its audit, both its calibration pairs and gates; no prior (none reads it)
        shared = SharedBeliefs(every)

        def audit(path: Path) -> dict[str, float]:
            return draw_audit.draw_cells(shared.run(path, budgets), thresholds, gamma, nominal=nominal, resamples=2, seed=0)

        def pair(cal: Path, test: Path) -> tuple[dict[str, float], dict[str, float]]:
            """Table III's calibrated cells and the random-probe gates on ``test``, calibrated on ``cal``."""
            cells = draw_audit.fresh_calibration_cells(shared.run(cal, budgets), shared.run(test, budgets), budgets,
                                                       alpha=self.p.alpha)
            return cells, draw_audit.fresh_gate_cells(shared.run(cal, every), shared.run(test, every), alpha=self.p.alpha)

        self.progress("explain: Table III on fresh draws", 0, len(drawn))
        with large_arrays_apart():  # two whole-run traces held: the commits' arrays leave no holes in the heap
            self._audit_draws([deployed.path for _, deployed, _ in drawn], audit, pair, shared, parts)

    def _audit_draws(self, paths: list[Path], audit: Callable[[Path], dict[str, float]],
                     pair: Callable[[Path, Path], tuple[dict[str, float], dict[str, float]]], shared: SharedBeliefs,
                     parts: dict[str, list[dict[str, float]]]) -> None:
        """:meth:`_draw_audit`'s loop: the first draw audited alone, the others in cyclic calibration pairs."""
        check, *fresh = paths
        parts["audit"] = [audit(check)]
        shared.drop(check)
        if len(fresh) > 1:  # each fresh draw tested under a calibration on the next one (cyclic): both draws vary
            self.progress("explain: Table III and random-probe gates with fresh calibration draws", 0, len(fresh))
            audits, pairs = cyclic_pairs(fresh, pair, shared, first=audit)
            parts["audit"] += audits
            parts["audit_fresh_cal"] = [cells for cells, _ in pairs]
            parts["gates_fresh_cal"] = [gate for _, gate in pairs]
        else:
            parts["audit"] += [audit(path) for path in fresh]

    def _draw_faults(self, drawn: list[tuple[str, Any, Any]], parts: dict[str, list[dict[str, float]]]) -> None:
        """The fault harness's none, boundary and particle arms replayed on each fresh draw's corrected run
        (``draw_faults``): the range of Table VIII's cells and Fig. 7's particle signature over draws."""
        p = self.p
        self.progress("explain: fault harness on fresh draws", 0, len(drawn))
        cells = [draw_faults.draw_cells(corrected, p.faults, p.sigma, p.budgets["random"]) for _, _, corrected in drawn]
        parts["faults"] = cells

    # ------------------------------------------------------------------ boundary fault and robust filters
    def boundary_fault(self) -> None:
        """The boundary fault by stratum, its fix, Test C; the whole-cluster escapes and the strata of the test
        runs: ``stored.harness_keys`` of the insertion study's stored rows (what verify recomputes)."""
        names = ("C_random", "C_random_corrected", "C_cover", "C_cover_corrected", "B_test_random")
        keys = stored.harness_keys(self.fault_episodes(), {n: self.load(n).episodes for n in names}, self.tables["schedules"],
                                   k_cover=self.p.budgets["cover"], k_random=self.p.budgets["random"],
                                   edge=self.cfg["stratum_edge_mm"], boot=self.boot,
                                   expected=self.res["instance_generator"].get("B_test_random.expected_share", 0.3))
        for group, values in keys.items():
            self.res[group].update(values)

    def robust(self) -> None:
        """The mixture's cost when the model is right, at every epsilon; its optimism on Test C."""
        p, r = self.p, self.p.robust
        kmax = p.budgets["random"]
        base = self.load("faults_base")
        parts = [_probe(base.episodes, kmax).assign(part="right_base", epsilon=float("nan"))]
        eps_grid = r.epsilons[:1] if self.quick else [*r.epsilons, *self.cfg["mixture_extra_epsilons"]]
        for i, eps in enumerate(eps_grid):
            self.progress("explain: mixture when right", i, len(eps_grid))
            belief = {"likelihood": "mixture", "epsilon": float(eps), "mixture_low": r.mixture_range[0],
                      "mixture_high": r.mixture_range[1]}
            ep = replay_at(base, {"belief": belief}, kmax)  # only the final budget is read (``replay_final``)
            parts.append(_probe(ep, kmax).assign(part="right_mixture", epsilon=float(eps)))
        chosen = json.loads(json.dumps(self.insertion_results()["robust"]["chosen"]))
        eps = float(chosen.get("mixture", r.epsilons[0]))
        belief = {"likelihood": "mixture", "epsilon": eps, "mixture_low": r.mixture_range[0], "mixture_high": r.mixture_range[1]}
        c_old = self.load("C_random")
        ep = replay_at(c_old, {"belief": belief}, kmax)
        parts.append(_probe(ep, kmax).assign(part="testc_mixture", epsilon=eps))
        self.stored[robust_rows.STORED] = robust_rows.table(parts)
        self.res["robust"].update(robust_rows.keys(self.stored[robust_rows.STORED], _probe(c_old.episodes, kmax),
                                                   self.insertion_results()["robust"], self.boot))

    # ------------------------------------------------------------------ PhysX
    def physx(self) -> None:
        """Our PhysX capture window, and the analytic scene with the paper's PhysX boundary and window."""
        out, p, e = self.res["physx_capture"], self.p, self.cfg["physx_emulation"]
        path = self.root / "engines" / "results" / "results.json"
        if path.is_file():
            out.update(engines_x.physx_ours(json.loads(path.read_text())["results"]["scans"]))
        self.progress("explain: emulated PhysX scene", 0, 1)
        emulated = runs.emulated_engine_runs(p, self.runs, e["boundary_offset"], e["capture_scale"], self.workers)
        instances = emulated["deployed"].instances.set_index("instance_id")
        kmax = p.budgets["random"]
        parts = []
        for variant, run in emulated.items():
            rows = _probe(run.episodes, kmax)
            parts.append(rows.assign(variant=variant, true_c=instances.loc[rows["instance_id"], "true_c"].to_numpy(float)))
        self.stored[engines_x.EMULATED] = engines_x.emulated_table(parts)
        out.update(engines_x.emulated_keys(self.stored[engines_x.EMULATED], e["capture_scale"], self.boot))

    # ------------------------------------------------------------------ GRU
    def gru(self) -> None:
        """Why the GRU interval is wider than the paper's, its power, and a retrained seed's tolerance."""
        out = self.res["gru"]
        path = self.root / "gru" / "results" / "results.json"
        if not path.is_file():
            out["available"] = 0
            return
        r = json.loads(path.read_text())["results"]
        episodes = self.root / "gru" / "results" / "gru_episodes.parquet"
        per_episode = pd.read_parquet(episodes) if episodes.is_file() else None
        out.update(gru_study.summary_keys(r, per_episode, self.boot, self.cfg["gru_paper_interval"]))  # what verify recomputes
        runs_dir = self.root / "breadth" / "runs"
        pipeline = runs_dir / ("push2d-quick" if self.quick and (runs_dir / "push2d-quick").is_dir() else "push2d")
        if pipeline.is_dir():  # its keys join the group once the later steps are done (``Background``)
            self.progress("explain: GRU seed 0 retrained (in a process of its own, beside the later steps)", 0, 1)
            self.submit(out.update, gru_study.retrain_tolerance, self.root / "gru" / "results", pipeline,
                        self.runs, self.quick)

    def _later(self, group: str, step: Callable[[], None], needs: tuple[str, ...]) -> tuple[Callable[[], None],
                                                                                             Callable[[], None]]:
        """``step`` run later, once the targets ``needs`` are done (side by side they may still be running),
        with its keys put where running it in place would have put them in ``group``: the first callable
        marks that place, the second runs it."""
        place: list[int] = []

        def run() -> None:
            if self.ready is not None:
                self.ready(needs)
            values = self.res[group]
            with self.reads.paused():
                before = list(values.items())
            step()
            with self.reads.paused():
                added = list(values.items())[len(before):]
            values.clear()
            values.update(before[:place[0]] + added + before[place[0]:])

        return lambda: place.append(len(self.res[group])), run

    def aside(self, *steps: Callable[[Any], None], needs: tuple[str, ...] | None = None) -> Callable[[], Any]:
        """A ``steps`` entry: ``steps`` (module-level functions of the job, run in this order on a job of their own)
        set aside to a process of their own (``Background``) beside the later steps, their keys put where running
        them here would have put them. Only for steps that read stored inputs (the root's runs and results, the
        settings) and runs earlier steps wrote, never what later steps write or hold; a step that reads another's
        rows goes with it (``run_aside`` refuses what cannot be merged in order). ``needs``: the late needs
        (``ready``) they read, waited for before they are set aside (None: all of them)."""
        def submit() -> Any:
            if self.ready is not None and needs != ():
                self.ready(needs)  # the job aside takes its needs as done
            places = {group: len(values) for group, values in self.res.items()}
            label = ", ".join(_name(s) for s in steps)
            self.progress(f"explain: set aside to a process of its own: {label}", 0, 1)
            job = self.reads.submitted(label)
            return self._hand_on(job, lambda filled: self._merge(filled, places, job), run_aside, self.root,
                                 self.quick, self.workers, self.cfg, steps)

        return submit

    def split(self, plan: Callable[[Any], pieces.Pieces | None], needs: tuple[str, ...] | None = None) -> Callable[[], Any]:
        """A ``steps`` entry: the sweep ``plan(self)`` cuts into pieces (``pieces``), each set aside as a process of
        its own, longest first; once the last is handed on, their results combined and merged as one job set aside
        here (``aside``) would have been: the same keys in the same places, the same stored rows. ``plan`` runs
        here (it reads the settings and stored inputs only); ``needs`` as :meth:`aside`'s."""
        def submit() -> None:
            if self.ready is not None and needs != ():
                self.ready(needs)
            cut = plan(self)
            if cut is None:
                return
            places = {group: len(values) for group, values in self.res.items()}
            label = _name(plan)
            self.progress(f"explain: set aside to {len(cut.calls)} processes of their own: {label}", 0, 1)
            job, results = self.reads.submitted(label), {}

            def then(i: int, result: Any) -> None:
                results[i] = result
                if len(results) == len(cut.calls):  # the last piece handed on: all of them, merged as one job
                    self._merge(pieces.gather(cut, results), places, job)

            for i in cut.order():
                fn, args = cut.calls[i]
                self._hand_on(job, functools.partial(then, i), pieces.timed, fn, *args)

        return submit

    def submit(self, then: Callable[[Any], None], fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)`` (a module-level function of picklable arguments) in a process of its own
        (``Background.submit``), its result handed to ``then`` in this process. What ``then`` writes into the
        results, stored rows or tables is recorded as this job's, so no later step may read it before
        :meth:`wait_aside` (``lanes``)."""
        return self._hand_on(self.reads.submitted(_name(fn)), then, fn, *args)

    def _hand_on(self, job: int, then: Callable[[Any], None], fn: Callable[..., Any], *args: Any) -> Any:
        def hand_on(result: Any) -> None:
            with self.reads.recording(job):
                then(result)

        return self.background.submit(hand_on, fn, *args)

    def wait_aside(self) -> None:
        """Wait for every job set aside so far and merge it: a later step may then read what they fill."""
        self.background.finish()
        self.reads.waited()

    def _merge(self, filled: dict[str, Any], places: dict[str, int], job: int) -> None:
        """What job aside ``job`` filled, each group's keys where they were when it was set aside
        (after those of the jobs set aside before it: they ran first in place)."""
        for group, added in filled["res"].items():
            values = self.res[group]
            at = places[group] + self._merged.get(group, 0)
            self._merged[group] = self._merged.get(group, 0) + len(added)
            with self.reads.paused():  # a rewrite of the group: only ``added`` is the job's
                items = list(values.items())
                values.clear()
                values.update(items[:at] + list(added.items()) + items[at:])
        # the rewrites above are paused; the rows and tables below are recorded as they are written (``_hand_on``)
        self.reads.filled(job, {("res", g, k) for g, added in filled["res"].items() for k in added})
        self.stored.update(filled["stored"])
        self.tables.update(filled["tables"])
        for label, wall, cpu, children in filled["steps"]:
            timing.logger.info("%s (aside): %.1f s wall, %.1f s CPU (+%.1f s in worker processes)", label, wall, cpu,
                               children)
        timing.logger.info("(aside: peak %.0f MB)", filled["peak_mb"])

    def run(self, out: Path) -> Path:
        out.mkdir(parents=True, exist_ok=True)
        self.progress("explain: paper's cover schedule on Split B", 0, 1)
        paper = runs.schedule_runs(self.p, COVER_SCHEDULE, self.runs, self.workers)
        place_physx, physx_coverage = self._later("missing", self.physx_coverage, ("engines",))
        steps = [self.missing, place_physx, lambda: self.committed_pool(paper), lambda: self.margins(paper),
                 self.resplits_paper_schedule,  # the steps set aside here read only the insertion study and it
                 self.aside(ex5_calibration.run, ex9_calibration.run, ex12_simultaneous.run, ex15_readings.run,
                            ex28_plateau.run, ex35_pools.run, needs=()),  # E118 (ex15_readings) joins the rows ex5 and
                 # ex9 store; E205 (ex35_pools) E56's stored fresh pools, and runs the rest
                 self.aside(ex30_fresh.run, needs=()),  # E190, E191: the insertion study's stored runs only
                 self.aside(ex33_aim.run, needs=()),  # E199, E200: the insertion study's stored runs only
                 self.split(ex38_physx.pieces, needs=()),  # E214, E216: PhysX scans off the protocol alone, an arm a job
                 self.aside(ex40_solver.run, needs=()),  # E226: PhysX solver iteration sweep, the protocol alone
                 self.aside(ex36_testc.run, needs=()),  # E208: Test C's cover run rerun (MuJoCo), paper's schedule
                 self.aside(ex7.run, ex37_filters.run, needs=()),  # E212/E213 replay the harness draws ex7 runs
                 self.aside(ex13.mixture, needs=()), self.aside(ex17.tiebreak, needs=()),
                 self.instance_generator, self.draw_runs, self.aside(draw_summaries, needs=()), self.boundary_fault,
                 self.aside(ex20.run, ex31_shift.run, ex36_coverage.run, needs=()),  # E144-E146, E193, E209: the
                 # stored random test run and the fresh draws on disk
                 self.aside(ex23.run, needs=()),  # E162/E163: the fresh draws and the Split B random runs, re-committed
                 self.aside(ex34_fixed.run, needs=()),  # E203/E204: Table III's run, one MuJoCo tap put first, re-committed
                 self.aside(ex43_setonly.run, needs=()),  # E232: Table III's run re-committed at t_k without the margin
                 self.robust, physx_coverage, self.physx,
                 lambda: (self.ready and self.ready(), self.gru()), lambda: more.run(self),
                 lambda: ex15_union.run(self), self.aside(ex18_grasp.run, needs=()),  # E133: frozen config only
                 self.aside(ex26_grasp.run, needs=()),  # E178/E179: frozen config only, squeeze patched
                 self.aside(ex22.exact, ex22.magnitude, needs=("breadth",)),  # E156-E158: stored breadth rows, closed forms
                 self.aside(ex25.uniform, ex32.floor, needs=("breadth",)),  # E174-E177, E196/E197: stored breadth rows
                 self.aside(ex27.torque, needs=("breadth",)),  # E182-E184: the stored hinge run, MuJoCo reruns
                 self.aside(ex41_slop.run, needs=("engines",)),  # E228: the same stored truths, contact slops (one
                 # job of about 300 s, submitted before E218's shorter points)
                 self.split(ex39_pybullet.pieces, needs=("engines",)),  # E218: the engines study's stored scans, reruns,
                 # a grid point a job
                 lambda: ex19.run(self),  # E138 reads the prior sweep's darts runs (more.run)
                 lambda: ex4.run(self),
                 lambda: ex6.run(self, paper),
                 lambda: ex8.run(self), lambda: ex10.run(self, paper),
                 self.aside(ex11.run, ex19.cone),  # E139 (ex19.cone) re-executes the pool ex11 runs
                 lambda: ex16.run(self), lambda: ex13.surprise(self, paper),
                 lambda: ex14.run(self, paper),
                 lambda: ex17.band(self, paper, COVER_SCHEDULE[0]),
                 self.aside(ex21.run, needs=()),  # E150/E151: the paper's-schedule runs and the pool's, stored
                 self.aside(ex24.run, needs=()),  # E168-E170: the same stored runs, other replays
                 self.aside(ex29_band.run, needs=()),  # E187: the same stored runs, the claim's and Table III's
                 self.aside(ex37_adjusted.run, needs=()),  # E211: the paper's-schedule runs, the gates recomputed
                 lambda: ex12_distinct.run(self),
                 lambda: ex18_share.run(self)]  # last: it waits for E118's and E119's rows
        self.run_steps(steps)
        margins = [t for name, t in self.tables.items() if name.startswith("margin_")]
        if margins:
            write_with(out / "margin_per_gamma.parquet",
                       lambda f: pd.concat(margins, ignore_index=True).to_parquet(f, compression="zstd"))
        if "draws" in self.tables:
            write_with(out / stored.DRAWS, self.tables["draws"].drop(columns="schedule").to_parquet)
        for name, file in (("breadth_prior", more.breadth.STORED), ("schedules", stored.SCHEDULES),
                           ("calibration_instances", calibration_rows.MARGIN_INSTANCES),
                           ("calibration_sums", calibration_rows.MARGIN_SUMS),
                           ("cells", stored.CELLS), ("mixture_noise", more.mixture_x.STORED)):
            if name in self.tables:  # the rows verify recomputes the summaries from (``stored``)
                write_with(out / file, lambda f, t=self.tables[name]: t.to_parquet(f, compression="zstd"))
        self._store_calibrations(out)
        for file, table in self.stored.items():
            write_with(out / file, lambda f, t=table: t.to_parquet(f, compression="zstd"))
        payload = {"results": plain(self.res)}
        write_text(out / "results.json", json.dumps(payload, indent=1, allow_nan=False))
        write_text(out / "explain.md", summary_markdown(payload["results"]))
        return out

    def run_steps(self, steps: list[Callable[[], Any]]) -> None:
        """``steps`` in order, then the jobs set aside handed on; checks that no step read what a job set aside
        before it fills (``lanes.Reads.check``: such a read would depend on the schedule).

        The C heap's free pages go back after each step (``release_free_heap``): a step's peak then starts from
        what is live, not from the high-water mark of the steps before it (the last step's import of
        ``scipy.stats``, about 50 MB, sat on top of earlier replays' freed heap: 526 MB; decisions.md, "The reproduction's
        peak back under 500 MB")."""
        try:
            for i, step in enumerate(steps):
                self.reads.step = i
                self.progress("explain", i, len(steps))
                step()
                release_free_heap()
            self.reads.step = len(steps)
            self.progress("explain: waiting for the steps in a process of their own", 0, 1)
            self.background.finish()  # each fills groups (and stored rows) no other step fills
        finally:
            self.background.close()
        self.progress.close()
        self.reads.check()

    def _store_calibrations(self, out: Path) -> None:
        """The re-executed commits and the step's own runs' episodes (the insertion study's writers and columns)."""
        from probecommit.studies.insertion import store_commits, store_episodes

        store_commits(self.commits, out / calibration_rows.COMMITS)
        if self.episodes:
            methods = lambda name: ["probe_robust", "blind_robust"] if name == calibration_rows.PAPER_TEST else ["probe_robust"]  # noqa: E731
            rows = pd.concat([ep[ep["method"].isin(methods(name))].assign(run=name) for name, ep in self.episodes.items()],
                             ignore_index=True)
            store_episodes(rows, out / calibration_rows.EPISODES, extra=("run",))


def draw_summaries(job: Explain) -> None:
    """``Explain.draws`` as a step set aside (``Explain.aside``), after ``Explain.draw_runs`` wrote the draws in place
    (later steps read them: ex12, ex14); here they resume. Its audits and gates hold two whole-run belief traces at
    once (``SharedBeliefs``, about 110 MB each) above what the explain process already holds: in a process of its
    own they never add to the explain process's peak (issue 42, target 4)."""
    job.draws()


def _name(step: Callable[..., Any]) -> str:
    return f"{step.__module__.rsplit('.', 1)[-1]}.{step.__name__}"


def run_aside(root: Path, quick: bool, workers: int, config: dict[str, Any],
              steps: tuple[Callable[[Any], None], ...]) -> dict[str, Any]:
    """In a process of its own (``Explain.aside``): ``steps`` run one after the other on a fresh job whose needs are
    done; the groups, stored rows and tables they filled, and their clocks.

    Raises:
        RuntimeError: a step filled what the target concatenates in step order (commits, episodes, margin
            tables): merged later it would move.
    """
    from probecommit.tasks.base import shared_engine_answers

    job = Explain(root, quick, lambda *a: None, workers, config)
    try:
        with shared_engine_answers():  # as the target's own process (``schedule.run_target``)
            for step in steps:
                step(job)
            job.background.finish()
    finally:
        job.background.close()
    job.progress.close()
    if job.commits or job.episodes or any(name.startswith("margin_") for name in job.tables):
        raise RuntimeError(f"{', '.join(map(_name, steps))}: fills rows kept in step order; run it in place")
    return {"res": {g: v for g, v in job.res.items() if v}, "stored": job.stored, "tables": job.tables,
            "steps": job.progress.steps, "peak_mb": timing.peak_mb()}


def plain(o: Any) -> Any:
    """JSON-ready values. A value the data leave undefined (NaN: no escapes to rank, one draw for an SD, an
    empty stratum; a quick run has many) is ``null``, an interval with an undefined end wholly so: verify
    refuses an undeclared NaN, and a claim reading ``null`` is unresolved, not compared."""
    if isinstance(o, dict):
        return {str(k): plain(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        if len(o) == 3 and all(isinstance(v, (float, np.floating)) for v in o) and any(np.isnan(v) for v in o):
            return None
        return [plain(v) for v in o]
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating, float)):
        if np.isnan(o):
            return None
        return "inf" if np.isinf(o) else float(o)  # verify refuses infinities; the conformal "+inf" is spelled out
    if isinstance(o, (np.bool_, bool)):
        return int(o)
    return o


def _fmt(v: Any) -> str:
    if v is None:
        return "--"  # undefined with these data
    if isinstance(v, (list, tuple)) and len(v) == 3:
        return f"{v[0]:.3f} [{v[1]:.3f}, {v[2]:.3f}]"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def summary_markdown(res: dict[str, dict[str, Any]]) -> str:
    """Every key with its value, one table per group (the margin curve is in its parquet)."""
    lines = ["# Explanations: every measured key", ""]
    for group, values in res.items():
        lines += [f"## {group}", "", "| key | value |", "|---|---|"]
        lines += [f"| explain:results.{group}.{k} | {_fmt(v)} |" for k, v in values.items()
                  if not (group == "margin_per_gamma" and re.search(r"\.g\d", k))]
        lines.append("")
    return "\n".join(lines)


def reproduce_explain(root: str | Path, quick: bool = False, progress: Progress | None = None, workers: int = 1,
                      config_path: str | Path | None = None, ready: Callable[..., None] | None = None) -> Path:
    """Run every explanation into ``<root>/explain/results`` (``ready``: see ``Explain.ready``)."""
    root = Path(root)
    job = Explain(root, quick, progress or (lambda *a: None), workers, load_explain_config(config_path), ready)
    return job.run(root / "explain" / "results")
