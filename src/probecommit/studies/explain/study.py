"""``probecommit reproduce explain``: the measurements behind every difference from the paper.

Reads the run directories of ``reproduce insertion`` and ``reproduce engines`` (and the GRU's
results when present) under the same root, adds a few controlled runs (:mod:`.runs`), and
writes ``results.json``: ``{"results": {group: {name: value}}}`` with values numbers or
``[point, lo, hi]`` cluster-bootstrap triples. ``EXPLAIN_KEYS.md`` at the repository root says
what each key measures.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd
import yaml

from probecommit.audit.conformal import simultaneous_threshold
from probecommit.audit.stats import paired_bootstrap, percentile_interval, resample_counts
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.studies.explain import draw_audit, draw_faults, generator, more, resplits, runs, stored, surprise_variants
from probecommit.studies.explain import ex6
from probecommit.studies.explain import gru as gru_study
from probecommit.studies.explain.margin import margin_curve
from probecommit.studies.explain.pool import gate_pools
from probecommit.studies.explain.stats import (capture_failure, conformal_quantile_draws, equivalence_power, interval_se,
                                                margin_draws)
from probecommit.studies.paper_values import PRINTED
from probecommit.studies.paper_values import value as paper_value
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

    def __init__(self, root: Path, quick: bool, progress: Progress, workers: int, config: dict[str, Any]) -> None:
        protocol = load_protocol()
        self.p: Protocol = protocol.quick_version() if quick else protocol
        self.quick = quick
        self.root = Path(root)
        self.ins = self.root / "insertion" / "runs"
        self.runs = self.root / "explain" / "runs"
        self.progress = progress
        self.workers = workers
        self.cfg = config
        self.boot = dict(resamples=self.p.bootstrap.resamples, seed=self.p.bootstrap.seed)
        self.res: dict[str, dict[str, Any]] = {g: {} for g in (
            "missing", "committed_pool", "instance_generator", "margin_per_gamma", "thresholds", "gru", "physx_capture",
            "boundary_fault", "robust", *more.GROUPS,
            *ex6.GROUPS)}
        self.tables: dict[str, pd.DataFrame] = {}
        #: Stored rows written beside results.json as they are, by file name (``more``'s steps).
        self.stored: dict[str, pd.DataFrame] = {}
        self._loaded: dict[str, Any] = {}

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
        """Every commit gate under random probes (the paper reports only that posterior variance is lowest)."""
        from probecommit.runner.calibration import gates

        m = self.res["missing"]
        self.progress("explain: random-probe gates", 0, 1)
        record: list[pd.DataFrame] = []  # the rows the gates read (ex6's E63 compares them over one range)
        result = gates(self.load("B_cal_random"), self.load("B_test_random"), alpha=self.p.alpha, **self.boot,
                       chunk_instances=48, record=record)
        self.tables["random_gates_record"] = record
        pools = gate_pools(result)
        areas = {name: pools.get(f"{name}.area", float("nan")) for name in ("raw", "adjusted", "posterior_variance")}
        m.update({f"gate_area_random.{name}": area for name, area in areas.items()})
        m["gate_area_random.lowest_is_posterior_variance"] = int(min(areas, key=areas.get) == "posterior_variance")
        # Areas span each gate's own attainable range; the mean failure over it compares them on equal terms.
        means = {name: pools.get(f"{name}.mean_failure", float("nan")) for name in areas}
        m.update({f"gate_mean_failure_random.{name}": v for name, v in means.items()})
        m["gate_mean_failure_random.lowest_is_posterior_variance"] = int(min(means, key=means.get) == "posterior_variance")
        self.res["committed_pool"].update({f"random.{k}": v for k, v in pools.items()})

    def _corrected_thresholds(self) -> None:
        """The corrected random-probe simultaneous threshold, and two stored thresholds recomputed."""
        p, t = self.p, self.res["thresholds"]
        self.progress("explain: corrected random calibration", 0, 1)
        corrected = runs.corrected_replay(self.ins / "B_cal_random", self.runs, p.delta)
        budgets = self.cfg["random_budgets"]
        self.res["missing"]["simultaneous_threshold_random_corrected"] = simultaneous_threshold(
            _probe(corrected.episodes), budgets, p.alpha)
        t["simultaneous_random_original_recomputed"] = simultaneous_threshold(
            _probe(self.load("B_cal_random").episodes), budgets, p.alpha)
        t["simultaneous_cover_corrected_recomputed"] = simultaneous_threshold(
            _probe(self.load("B_cal_cover_corrected").episodes), list(range(1, p.budgets["cover"] + 1)), p.alpha)

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
        for label, run in (("ours", self.load("B_test_cover")), ("paper_schedule", paper_test)):
            aucs = surprise_variants.variant_aucs(run, _probe(run.episodes), [1, k], k, **self.boot)
            self.res["missing"].update({f"surprise_variants.{label}.{key}": v for key, v in aucs.items()})

    def _schedule_failure(self, paper_schedule: dict[str, Any]) -> None:
        """Table IV's calibrated rows and the cost of calibration under the paper's schedule (the schedules'
        failures on the same instances are ``stored.pool_keys``')."""
        from probecommit.runner.calibration import calibrate

        c, b, k = self.res["committed_pool"], self.boot, self.p.budgets["cover"]
        self.progress("explain: calibration under the paper's schedule", 0, 1)
        cal = calibrate(paper_schedule["cal"], paper_schedule["test"], alpha=self.p.alpha, budgets=list(range(1, k + 1)),
                        **b, chunk_instances=48)
        for row in cal.cost.to_dict("records"):
            name = str(row["setting"]).replace(" + ", "_").replace(" ", "_")
            c[f"schedule.B_test.paper_schedule.cost_table.{name}"] = [row["failure"], row["failure_lo"], row["failure_hi"]]
        for row in cal.cost_differences.to_dict("records"):
            key = COST_LABELS[(row["baseline"], row["treatment"])]
            self.res["missing"][f"cost_of_calibration_paper_schedule.{key}"] = [row["difference"], row["lo"], row["hi"]]
        self.res["margin_per_gamma"]["paper_schedule.gamma_calibrate"] = cal.margin.gamma

    def resplits_paper_schedule(self) -> None:
        """The 50 re-splits of the 192-instance cover pool under the paper's schedule (``resplits``)."""
        self.progress("explain: re-splits under the paper's schedule", 0, 1)
        out = resplits.run(self.p, COVER_SCHEDULE, self.runs, self.workers)
        self.res["committed_pool"].update({f"resplits.paper_schedule.{k}": v for k, v in out.items()})

    # ------------------------------------------------------------------ margin and thresholds
    def margins(self, paper_schedule: dict[str, Any]) -> None:
        g, t, p = self.res["margin_per_gamma"], self.res["thresholds"], self.p
        k = p.budgets["cover"]
        budgets = list(range(1, k + 1))
        for label, run in (("ours", self.load("B_cal_cover")), ("paper_schedule", paper_schedule["cal"])):
            self.progress(f"explain: margin curve ({label})", 0, 1)
            curve = margin_curve(run, budgets, p.alpha, _final_escape(run.episodes, k))
            table = curve["table"]
            kept = [c for c in table.columns if not c.startswith("sum_")]  # sums are the rule's; the means are published
            self.tables[f"margin_{label}"] = table[kept].assign(schedule=label)
            g.update(stored.margin_keys(self.tables[f"margin_{label}"]))  # what verify recomputes from the stored curve
            g[f"{label}.gamma"] = curve["gamma"]
            g[f"{label}.gamma_covered_only"] = curve["gamma_covered_only"]
            g[f"{label}.escaped_share_cal"] = float(_final_escape(run.episodes, k).mean())
            t[f"{label}.t_{k}"] = curve["thresholds"][k]
            t[f"{label}.simultaneous"] = curve["simultaneous_threshold"]
            t[f"{label}.distribution_free_margin"] = curve["distribution_free_margin"]
            s = curve["scores_final"]
            t[f"{label}.share_scores_final_above_paper_t"] = float((s > paper_value("T02-t5-cover.t5")).mean())
            t[f"{label}.share_scores_final_escaped"] = float((s > 1.0).mean())
            worst = curve["worst_budget_optimism"]
            t[f"{label}.share_worst_optimism_above_paper_df"] = float(
                (worst > paper_value("T04-distribution-free-margin.cover")).mean())
            for kk, value in curve["gamma_per_budget"].items():
                g[f"{label}.gamma_at_k{kk}"] = value
            self._sampling_intervals(label, curve, k)
            gammas, pred, real = curve["instance_sums"]
            beyond = np.abs(curve["x_hole"]) > self.cfg["stratum_edge_mm"]
            share = (10.0 - self.cfg["stratum_edge_mm"]) / 10.0  # the +-10 mm box's share beyond the edge
            weights = np.where(beyond, share / max(beyond.mean(), 1e-12), (1 - share) / max((~beyond).mean(), 1e-12))
            g[f"{label}.gamma_standardized"] = float(margin_draws(gammas, pred, real, weights[None, :])[0])
            g[f"{label}.gamma_inside"] = float(margin_draws(gammas, pred, real, (~beyond).astype(float)[None, :])[0])
            g[f"{label}.gamma_beyond"] = float(margin_draws(gammas, pred, real, beyond.astype(float)[None, :])[0])
            if label == "ours":
                nu_curve = margin_curve(run, budgets, p.alpha, None, set_calibrated=False)
                g["ours.gamma_nu_executor"] = nu_curve["gamma"]
                g["ours.optimism_at_gamma_1_nu_executor"] = float(
                    nu_curve["table"].iloc[0].mean_realized - nu_curve["table"].iloc[0].mean_predicted)

    def _sampling_intervals(self, label: str, curve: dict[str, Any], k: int) -> None:
        """Cluster-bootstrap intervals of gamma, t_k, the simultaneous t and the distribution-free
        margin: how far a quantile of 96 calibration instances moves with the draw alone."""
        g, t, p = self.res["margin_per_gamma"], self.res["thresholds"], self.p
        gammas, pred, real = curve["instance_sums"]
        scores = curve["scores"]
        scores.index = scores.index.astype(str)
        order = np.sort(scores.index.to_numpy())
        counts = resample_counts(order.size, self.boot["resamples"], self.boot["seed"])
        draws = margin_draws(gammas, pred, real, counts)
        g[f"{label}.gamma_interval"] = [curve["gamma"], *percentile_interval(draws)]
        g[f"{label}.share_resamples_gamma_at_least_paper"] = float(np.mean(draws >= paper_value("T03-margin.cover") - 1e-12))
        t_draws = conformal_quantile_draws(scores.loc[order, k].to_numpy(float), counts, p.alpha)
        t[f"{label}.t_{k}_interval"] = [curve["thresholds"][k], *percentile_interval(t_draws)]
        t[f"{label}.share_resamples_t_{k}_at_most_paper"] = float(np.mean(t_draws <= paper_value("T02-t5-cover.t5")))
        worst = curve["worst_budget_optimism"]
        worst.index = worst.index.astype(str)
        df_draws = conformal_quantile_draws(worst.reindex(order).to_numpy(float), counts, p.alpha)
        t[f"{label}.distribution_free_margin_interval"] = [curve["distribution_free_margin"], *percentile_interval(df_draws)]
        t[f"{label}.share_resamples_df_at_least_paper"] = float(
            np.mean(df_draws >= paper_value("T04-distribution-free-margin.cover")))

    # ------------------------------------------------------------------ instance draws
    def instance_generator(self) -> None:
        out = self.res["instance_generator"]
        edge, seeds = self.cfg["stratum_edge_mm"], self.cfg["generator_seeds_quick" if self.quick else "generator_seeds"]
        low, high = -10.0, 10.0
        for name in ("A_cover", "B_cal_cover", "B_test_cover", "B_cal_random", "B_test_random", "C_cover", "C_random"):
            run = self.load(name)
            cfg = run.config.instances
            if cfg.sampling != "uniform":
                continue
            test = generator.generator_test(run.instances, cfg.split, cfg.seed, low, high, edge, seeds)
            out.update({f"{name}.{k}": v for k, v in test.items()})

    def draws(self) -> None:
        """Escape, failure and the boundary fix across fresh draws of the generator (analytic scene)."""
        out, p, b = self.res["instance_generator"], self.p, self.boot
        kmax, edge = p.budgets["random"], self.cfg["stratum_edge_mm"]
        count = self.cfg["fresh_draws_quick" if self.quick else "fresh_draws"]
        self.progress("explain: fresh draws of the generator", 0, 1)
        rows = []
        drawn = runs.fresh_draws(p, self.runs, count, self.workers)
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
        out["draws.analytic_equals_mujoco_escape_k8"] = int(
            abs(table.iloc[0]["escape_k8"] - mujoco["escaped"].mean()) < 1e-12)
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
        self.progress("explain: Table III on fresh draws", 0, len(drawn))
        cells = [draw_audit.draw_cells(deployed.path, thresholds, gamma, nominal=1 - self.p.alpha, resamples=2, seed=0)
                 for _, deployed, _ in drawn]
        parts["audit"] = cells
        fresh = [deployed.path for _, deployed, _ in drawn[1:]]
        if len(fresh) > 1:  # each fresh draw tested under a calibration on the next one (cyclic): both draws vary
            self.progress("explain: Table III with fresh calibration draws", 0, len(fresh))
            pairs = [draw_audit.fresh_calibration_cells(fresh[(i + 1) % len(fresh)], test, sorted(thresholds),
                                                        alpha=self.p.alpha) for i, test in enumerate(fresh)]
            parts["audit_fresh_cal"] = pairs
            self.progress("explain: random-probe gates on fresh draws", 0, len(fresh))
            gate_cells = [draw_audit.fresh_gate_cells(fresh[(i + 1) % len(fresh)], test, alpha=self.p.alpha)
                          for i, test in enumerate(fresh)]
            parts["gates_fresh_cal"] = gate_cells

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
        out, p, r = self.res["robust"], self.p, self.p.robust
        kmax = p.budgets["random"]
        base = self.load("faults_base")
        right = float(_probe(base.episodes, kmax)["realized"].mean())
        out["right_model.failure"] = right
        eps_grid = r.epsilons[:1] if self.quick else [*r.epsilons, *self.cfg["mixture_extra_epsilons"]]
        for i, eps in enumerate(eps_grid):
            self.progress("explain: mixture when right", i, len(eps_grid))
            belief = {"likelihood": "mixture", "epsilon": float(eps), "mixture_low": r.mixture_range[0],
                      "mixture_high": r.mixture_range[1]}
            ep, _ = replay_episodes(base, {"belief": belief}, chunk_instances=48)
            rows = _probe(ep, kmax)
            out[f"right_model.mixture_eps{eps:g}.failure"] = float(rows["realized"].mean())
            out[f"right_model.mixture_eps{eps:g}.changed_aims"] = float(
                (rows.set_index(["instance_id", "repeat"])["action"]
                 != _probe(base.episodes, kmax).set_index(["instance_id", "repeat"])["action"]).mean())
        chosen = json.loads(json.dumps(self.insertion_results()["robust"]["chosen"]))
        eps = float(chosen.get("mixture", r.epsilons[0]))
        belief = {"likelihood": "mixture", "epsilon": eps, "mixture_low": r.mixture_range[0], "mixture_high": r.mixture_range[1]}
        c_old = self.load("C_random")
        ep, _ = replay_episodes(c_old, {"belief": belief}, chunk_instances=48)
        rows, dep = _probe(ep, kmax), _probe(c_old.episodes, kmax)
        out["testc.deployed.optimism"] = float((dep["realized"] - dep["predicted"]).mean())
        out["testc.mixture.optimism"] = float((rows["realized"] - rows["predicted"]).mean())
        out["testc.mixture.escape"] = float(rows["escaped"].mean())
        out["testc.mixture.failure_change"] = _triple(paired_bootstrap(dep, rows, "realized", **self.boot).difference)
        res = self.insertion_results()["robust"]
        out["harness.deployed.optimism"] = float(res["deployed"]["optimism"][0])
        for family in ("mixture", "rejuvenation"):
            if family in res:
                out[f"harness.{family}.optimism"] = float(res[family]["optimism"][0])

    # ------------------------------------------------------------------ PhysX
    def physx(self) -> None:
        """Our PhysX capture window, and the analytic scene with the paper's PhysX boundary and window."""
        out, p, e = self.res["physx_capture"], self.p, self.cfg["physx_emulation"]
        path = self.root / "engines" / "results" / "results.json"
        if path.is_file():
            scans = json.loads(path.read_text())["results"]["scans"]
            if "sapien" in scans:
                out["ours.capture_ratio"] = float(scans["sapien"]["capture"]["ratio_mean"])
                out["ours.capture_ratio_sd"] = float(scans["sapien"]["capture"]["ratio_sd"])
                out["ours.boundary_offset"] = float(scans["sapien"]["boundary"]["delta"])
        self.progress("explain: emulated PhysX scene", 0, 1)
        emulated = runs.emulated_engine_runs(p, self.runs, e["boundary_offset"], e["capture_scale"], self.workers)
        instances = emulated["deployed"].instances.set_index("instance_id")
        kmax = p.budgets["random"]
        tables = {}
        for variant, run in emulated.items():
            rows = _probe(run.episodes, kmax).copy()
            c = instances.loc[rows["instance_id"], "true_c"].to_numpy(float)
            for scale_name, scale in (("paper_capture", e["capture_scale"]), ("model_capture", 1.0)):
                realized = capture_failure(rows["action"].to_numpy(), rows["z_true"].to_numpy(), c, scale)
                pre = f"emulated.{scale_name}.{variant}"
                out[f"{pre}.failure"] = float(realized.mean())
                out[f"{pre}.optimism"] = float((realized - rows["predicted"].to_numpy(float)).mean())
                tables[(scale_name, variant)] = rows.assign(realized=realized)
            out[f"emulated.{variant}.escape"] = float(rows["escaped"].mean())
            out[f"emulated.{variant}.episode_coverage"] = float(rows["covered"].mean())
            out[f"emulated.{variant}.cluster_coverage"] = float(rows.groupby("instance_id")["covered"].all().mean())
            stored = rows["realized"].to_numpy(float)
            mine = tables[("paper_capture", variant)]["realized"].to_numpy(float)
            out[f"emulated.{variant}.stored_equals_recomputed"] = int(np.array_equal(stored, mine))
        for scale_name in ("paper_capture", "model_capture"):
            for variant in ("mj_offset", "own_scan"):
                d = paired_bootstrap(tables[(scale_name, "deployed")], tables[(scale_name, variant)], "realized", **self.boot)
                out[f"emulated.{scale_name}.{variant}.paired_failure"] = _triple(d.difference)

    # ------------------------------------------------------------------ GRU
    def gru(self) -> None:
        """Why the GRU interval is wider than the paper's, its power, and a retrained seed's tolerance."""
        out = self.res["gru"]
        path = self.root / "gru" / "results" / "results.json"
        if not path.is_file():
            out["available"] = 0
            return
        r = json.loads(path.read_text())["results"]
        est, lo, hi = r["gru_minus_pipeline"]
        margin = float(r["equivalence_margin"])
        se = interval_se(lo, hi)
        out["available"] = 1
        out["difference"] = [est, lo, hi]
        out["se_implied"] = se
        out["seed_miss_sd"] = float(r["seed_miss_sd"])
        out["seed_sd_of_mean"] = float(r["seed_miss_sd"]) / np.sqrt(max(int(r["seeds"]), 1))
        for name, delta in (("power_at_zero", 0.0), ("power_at_estimate", est)):
            out[name] = equivalence_power(se, delta, margin)
        paper_lo, paper_hi = self.cfg["gru_paper_interval"]
        paper_se = interval_se(paper_lo, paper_hi)
        out["se_paper_implied"] = paper_se
        out["se_ratio"] = se / paper_se
        out["power_at_estimate_with_paper_se"] = equivalence_power(paper_se, est, margin)
        episodes = self.root / "gru" / "results" / "gru_episodes.parquet"
        if episodes.is_file():
            spread = gru_study.difference_spread(pd.read_parquet(episodes), **self.boot)
            out.update(spread)
            out["instances_for_paper_se"] = float(spread["instances"] * (se / paper_se) ** 2)
            out["power_at_estimate_two_way"] = equivalence_power(interval_se(*spread["two_way_interval"][1:]), est, margin)
        runs_dir = self.root / "breadth" / "runs"
        pipeline = runs_dir / ("push2d-quick" if self.quick and (runs_dir / "push2d-quick").is_dir() else "push2d")
        if pipeline.is_dir():
            self.progress("explain: GRU seed 0 retrained", 0, 1)
            out.update(gru_study.retrain_tolerance(self.root / "gru" / "results", pipeline, self.runs, self.quick))

    def run(self, out: Path) -> Path:
        out.mkdir(parents=True, exist_ok=True)
        self.progress("explain: paper's cover schedule on Split B", 0, 1)
        paper = runs.schedule_runs(self.p, COVER_SCHEDULE, self.runs, self.workers)
        steps = [self.missing, self.physx_coverage, lambda: self.committed_pool(paper), lambda: self.margins(paper),
                 self.resplits_paper_schedule,
                 self.instance_generator, self.draws, self.boundary_fault, self.robust, self.physx, self.gru,
                 lambda: more.run(self), lambda: ex6.run(self, paper)]
        for i, step in enumerate(steps):
            self.progress("explain", i, len(steps))
            step()
        margins = [t for name, t in self.tables.items() if name.startswith("margin_")]
        if margins:
            write_with(out / "margin_per_gamma.parquet", pd.concat(margins, ignore_index=True).to_parquet)
        if "draws" in self.tables:
            write_with(out / stored.DRAWS, self.tables["draws"].drop(columns="schedule").to_parquet)
        for name, file in (("breadth_prior", more.breadth.STORED), ("schedules", stored.SCHEDULES),
                           ("cells", stored.CELLS), ("mixture_noise", more.mixture_x.STORED)):
            if name in self.tables:  # the rows verify recomputes the summaries from (``stored``)
                write_with(out / file, lambda f, t=self.tables[name]: t.to_parquet(f, compression="zstd"))
        for file, table in self.stored.items():
            write_with(out / file, lambda f, t=table: t.to_parquet(f, compression="zstd"))
        payload = {"results": plain(self.res)}
        write_text(out / "results.json", json.dumps(payload, indent=1, allow_nan=False))
        write_text(out / "explain.md", summary_markdown(payload["results"]))
        return out


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
                      config_path: str | Path | None = None) -> Path:
    """Run every explanation into ``<root>/explain/results``."""
    root = Path(root)
    job = Explain(root, quick, progress or (lambda *a: None), workers, load_explain_config(config_path))
    return job.run(root / "explain" / "results")
