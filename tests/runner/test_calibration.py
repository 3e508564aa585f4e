"""Calibration and commit gates on run directories (runner.calibration), and the audit of a run directory."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from probecommit.audit.conformal import conformal_quantile
from probecommit.audit.margin import GAMMA_GRID
from probecommit.audit.metrics import audit_table
from probecommit.audit.pipeline import audit
from probecommit.runner.calibration import calibrate, gates

ROBOT = Path(__file__).parents[1] / "audit" / "data" / "robot_log.csv"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    from tests.conftest import cal_test_runs

    return cal_test_runs(tmp_path_factory.mktemp("runs"), (3, 4), count=8, repeats=3)


def _stored_probe(run_dir):
    from probecommit.runner.replay import load_run

    e = load_run(run_dir).episodes
    return e[(e.method == "probe_robust") & (e.status == "ok")]


def test_calibrate_on_runs(runs):
    res = calibrate(runs["cal"], runs["test"], alpha=0.2, resamples=200)
    cal = _stored_probe(runs["cal"])
    # Thresholds from the stored scores (beliefs are recomputed bit-identically).
    for k, t in res.thresholds.items():
        worst = cal[cal.k == k].groupby("instance_id")["score_s"].max()
        assert t == conformal_quantile(worst.to_numpy(), 0.2)
    worst_all = cal.groupby("instance_id")["score_s"].max()
    assert res.simultaneous_threshold == conformal_quantile(worst_all.to_numpy(), 0.2)
    assert res.n_calibration == 8 and res.budgets == [1, 2, 3, 4, 5]
    # The margin: the largest grid value satisfying the rule (scan stops there).
    assert res.margin.gamma in GAMMA_GRID
    s = res.margin.search
    assert s["satisfied"].iloc[-1] == res.margin.satisfied and not s["satisfied"].iloc[:-1].any()
    assert (s["mean_predicted"].iloc[-1] >= s["mean_realized"].iloc[-1]) == res.margin.satisfied
    # "original" columns are the stored test run's own audit.
    stored = audit_table(_stored_probe(runs["test"]), resamples=200)
    np.testing.assert_allclose(res.table3["cluster_coverage_original"], stored["cluster_coverage"])
    np.testing.assert_allclose(res.table3["optimism_original"], stored["optimism"])
    # Cost rows and their paired differences agree.
    cost = res.cost.set_index("setting")["failure"]
    d = res.cost_differences.set_index(["baseline", "treatment"])["difference"]
    assert d[("no calibration", "set calibration + margin")] == pytest.approx(
        cost["set calibration + margin"] - cost["no calibration"])
    assert "blind_robust" in cost.index
    assert 0 <= res.simultaneous_coverage["cluster_coverage"] <= 1
    assert res.to_dict()["gamma"] == res.margin.gamma


def test_gates_on_runs(runs):
    res = gates(runs["cal"], runs["test"], resamples=100)
    s = res.summary.set_index("signal")
    assert list(s.index) == ["raw", "adjusted", "posterior_variance", "oracle"]
    assert res.n_trajectories == 8 * 3 and res.budgets == [1, 2, 3, 4, 5]
    assert s.loc["oracle", "realized"] == 0.0
    assert (s["escaped_committed"] + s["escaped_rejected"]).nunique() == 1
    assert res.info["gamma"] in GAMMA_GRID and "surprise" in res.info


def test_calibrate_refuses_runs_of_different_models(tmp_path, runs):
    from probecommit.runner.study import run_study
    from tests.conftest import small_config

    other = run_study(small_config(name="o", instances={"split": "o", "count": 4, "seed": 9},
                                   model={"boundary": "corrected"}), tmp_path / "o").run_dir
    with pytest.raises(ValueError, match="differ in their 'model' settings"):
        calibrate(runs["cal"], other)


def test_audit_of_a_run_directory(runs):
    res = audit(runs["test"], resamples=100)
    assert set(res.table["method"]) == {"blind_bayes", "blind_robust", "probe_robust"}
    assert list(res.surprise["k"]) == [1, 2, 3, 4, 5]


def test_cli_commands(tmp_path, runs):
    from probecommit.cli.app import app

    cli = CliRunner()
    r = cli.invoke(app, ["audit", str(ROBOT), "-o", str(tmp_path / "a"), "--resamples", "200"])
    assert r.exit_code == 0, r.output
    assert {"audit.html", "audit.png", "audit.csv"} <= {p.name for p in (tmp_path / "a").iterdir()}
    html = (tmp_path / "a" / "audit.html").read_text()
    assert "data:image/png;base64," in html and "<table" in html and "http" not in html.split("<body>")[1][:200]

    bad = tmp_path / "bad.csv"
    bad.write_text(ROBOT.read_text().replace("0.30,0,0.0", "0.30,oops,0.0"))
    r = cli.invoke(app, ["audit", str(bad)])
    assert r.exit_code == 2 and "realized" in r.output and "oops" in r.output

    r = cli.invoke(app, ["calibrate", "--cal", str(runs["cal"]), "--test", str(runs["test"]),
                         "-o", str(tmp_path / "c"), "--resamples", "100"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "c" / "calibration.html").exists() and (tmp_path / "c" / "calibration.json").exists()
    r = cli.invoke(app, ["gates", "--cal", str(runs["cal"]), "--test", str(runs["test"]),
                         "-o", str(tmp_path / "g"), "--resamples", "100"])
    assert r.exit_code == 0, r.output
    curves = pd.read_csv(tmp_path / "g" / "gate_curves.csv")
    assert set(curves["signal"]) == {"raw", "adjusted", "posterior_variance", "oracle"}


@pytest.mark.skipif("fork" not in __import__("multiprocessing").get_all_start_methods(), reason="no fork here")
def test_calibrate_command_writes_the_same_files_with_and_without_helpers(tmp_path, runs, monkeypatch):
    """The command draws its report in forked helper processes (``process.forked``): every file it writes
    is the same bytes as when it draws them itself (the report's minute stamp aside)."""
    import re

    import probecommit.process.forked as forked
    from probecommit.cli.app import app

    written = {}
    for helpers in (True, False):
        monkeypatch.setattr(forked, "can_fork", lambda helpers=helpers: helpers)
        out = tmp_path / str(helpers)
        r = CliRunner().invoke(app, ["calibrate", "--cal", str(runs["cal"]), "--test", str(runs["test"]),
                                     "-o", str(out), "--resamples", "100"])
        assert r.exit_code == 0, r.output
        written[helpers] = {p.name: re.sub(rb"written [0-9-]+ [0-9:]+ UTC", b"written", p.read_bytes())
                            for p in out.iterdir()}
    assert {"calibration.html", "calibration.png", "calibration.pdf", "table3.csv"} <= set(written[True])
    assert written[True] == written[False]


def test_calibrate_command_keeps_its_large_arrays_in_the_heap(tmp_path, runs, monkeypatch):
    """The command's ``calibrate`` runs within ``large_arrays_in_heap`` (its passes' arrays reused in the
    heap, not mapped apart: docs/decisions.md, "cal3:"), and the setting ends with the command."""
    import probecommit.process.forked as forked
    import probecommit.runner.calibration as calibration
    from probecommit.cli.app import app
    from probecommit.errors import UsageError
    from probecommit.process import memory

    seen = []

    def stop(*args, **kwargs):
        seen.append(list(memory._in_heap))
        raise UsageError("stopped here")

    monkeypatch.setattr(forked, "can_fork", lambda: False)
    monkeypatch.setattr(calibration, "calibrate", stop)
    r = CliRunner().invoke(app, ["calibrate", "--cal", str(runs["cal"]), "--test", str(runs["test"]),
                                 "-o", str(tmp_path / "c")])
    assert "stopped here" in r.output and r.exit_code != 0
    assert seen == [[True]] and memory._in_heap == []


def test_runs_with_a_failed_trajectory(tmp_path, runs, monkeypatch):
    """A trajectory whose probing failed stays counted through calibration and gates."""
    import probecommit.runner.build as build
    from probecommit.runner.study import run_study
    from tests.conftest import small_config

    real_build = build.build_simulator
    calls = [0]  # shared by every unit's simulator: exactly one probe fails

    class Flaky:
        def __init__(self, sim):
            self._sim = sim

        def probe(self, theta, u, rng):
            calls[0] += 1
            if calls[0] == 7:  # second trajectory, second probe
                return float("nan") * self._sim.probe(theta, u, rng)
            return self._sim.probe(theta, u, rng)

        def __getattr__(self, name):
            return getattr(self._sim, name)

    monkeypatch.setattr(build, "build_simulator", lambda cfg: Flaky(real_build(cfg)))
    cfg = small_config(name="test", instances={"split": "test", "count": 8, "seed": 4}, repeats=3)
    run = run_study(cfg, tmp_path / "flaky").run_dir
    monkeypatch.undo()
    res = audit(run, resamples=100)
    probe = res.table[res.table.method == "probe_robust"]
    assert (probe["n_failed"] == 1).all() and (probe["n_episodes"] == 8 * 3 - 1).all()
    cal = calibrate(runs["cal"], run, resamples=100)
    assert (cal.audit_original["n_failed"] == 1).all()
    g = gates(runs["cal"], run, resamples=100)
    assert g.n_trajectories == 8 * 3 - 1 and g.n_dropped == 1


def test_in_sample_calibration_is_refused(runs):
    with pytest.raises(ValueError, match="share 8 instance"):
        calibrate(runs["test"], runs["test"])


def _stored_all(run_dir):
    from probecommit.runner.replay import load_run

    return load_run(run_dir).episodes


@pytest.mark.parametrize("chunk", [None, 3])
def test_calibration_recomputes_from_its_recorded_rows(runs, chunk):
    """What verify does: the result again from the recorded rows and the runs' stored episodes, equal to the
    last bit (chunked commits record the same rows as one pass); an edited recorded row moves a number."""
    from probecommit.runner.calibration import Recorder, calibration_from_tables

    record: list = []
    res = calibrate(runs["cal"], runs["test"], alpha=0.2, resamples=200, seed=5, chunk_instances=chunk, record=record)
    commits = Recorder(record).table()
    assert set(commits["request"]) == {"margin", "optimism", "set", "set_margin"}
    # The set-calibrated arm is read at the cost budget only, so only that budget is committed and kept.
    assert set(commits.loc[commits.request == "set", "k"]) == {res.cost_budget}
    # Only the margins the search read are kept.
    assert sorted(commits.loc[commits.request == "margin", "gamma"].unique()) == sorted(res.margin.search["gamma"])
    again = calibration_from_tables(commits, _stored_all(runs["cal"]), _stored_all(runs["test"]), 0.2,
                                    res.budgets, resamples=200, seed=5)
    pd.testing.assert_frame_equal(again.table3, res.table3)
    pd.testing.assert_frame_equal(again.cost, res.cost)
    pd.testing.assert_frame_equal(again.cost_differences, res.cost_differences)
    assert (again.margin.gamma, again.distribution_free_margin, again.thresholds, again.simultaneous_threshold,
            again.summary) == (res.margin.gamma, res.distribution_free_margin, res.thresholds,
                               res.simultaneous_threshold, res.summary)
    edited = commits.copy()
    row = edited.index[(edited.request == "set_margin") & (edited.k == 5)][0]
    edited.loc[row, "realized"] = 1.0 - edited.loc[row, "realized"]
    moved = calibration_from_tables(edited, _stored_all(runs["cal"]), _stored_all(runs["test"]), 0.2, res.budgets,
                                    resamples=200, seed=5)
    assert not moved.table3["optimism_calibrated"].equals(res.table3["optimism_calibrated"])


def test_gates_recompute_from_their_recorded_rows(runs):
    from probecommit.runner.calibration import Recorder, gates_from_commits

    record: list = []
    res = gates(runs["cal"], runs["test"], alpha=0.2, resamples=200, seed=5, record=record)
    commits = Recorder(record).table()
    again = gates_from_commits(commits, _stored_all(runs["cal"]), 0.2, res.budgets, resamples=200, seed=5)
    pd.testing.assert_frame_equal(again.curves, res.curves)
    pd.testing.assert_frame_equal(again.summary, res.summary)
    assert {k: again.info[k] for k in ("threshold", "gamma", "gamma_satisfied")} == \
        {k: res.info[k] for k in ("threshold", "gamma", "gamma_satisfied")}
    # The uncalibrated gate rows are the test run's own stored commits.
    stored = _stored_all(runs["test"])
    stored = stored[(stored.method == "probe_robust") & stored.k.isin(res.budgets)].set_index(["instance_id", "repeat", "k"])
    raw = commits[commits.request == "raw"].astype({"repeat": "int64"}).set_index(["instance_id", "repeat", "k"])
    np.testing.assert_array_equal(raw.loc[stored.index, "predicted"], stored["predicted"])


def test_calibration_summary_in_threads_equals_one_thread(runs, monkeypatch):
    """The summary's bootstraps run as jobs in two threads (``_summary``); each draws from its own
    generator of the integer seed, so the result is the one thread's, bit for bit (and the BLAS
    thread limit around them changes no product)."""
    import json

    from probecommit.tasks.base import ENGINE_THREADS_ENV

    def result(threads: str) -> str:
        monkeypatch.setenv(ENGINE_THREADS_ENV, threads)
        res = calibrate(runs["cal"], runs["test"], alpha=0.2, resamples=200)
        return json.dumps([res.to_dict(), res.margin.search.to_dict("list")], default=str, sort_keys=True)

    assert result("2") == result("1")


@pytest.mark.parametrize("stored", ["as run", "altered", "absent"])
def test_stored_thresholds_are_a_guess_the_recomputed_scores_check(runs, stored, monkeypatch):
    """calibrate searches the margin under the ``t_k`` of the calibration run's stored ``nu`` rows, in the
    pass that recomputes the scores (one pass over the run); stored rows that are not what the beliefs
    give (altered here) cost a second pass under the recomputed ``t_k``, and rows that give none (no
    probe rows) a scores pass first: the result and the recorded rows are the same bits in every case."""
    import json

    import probecommit.runner.calibration as calibration
    from probecommit.runner.calibration import Recorder
    from probecommit.runner.replay import LoadedRun, load_run

    def result(cal) -> tuple[str, pd.DataFrame]:
        record: list = []
        res = calibrate(cal, runs["test"], alpha=0.2, resamples=50, seed=5, chunk_instances=3, record=record)
        return json.dumps([res.to_dict(), res.margin.search.to_dict("list")], default=str, sort_keys=True), \
            Recorder(record).table()

    expected, expected_rows = result(runs["cal"])
    loaded = load_run(runs["cal"])
    episodes = loaded.episodes.copy()
    probe = episodes["method"] == "probe_robust"
    if stored == "altered":
        episodes.loc[probe, "score_s"] = episodes.loc[probe, "score_s"] * 0.5
    elif stored == "absent":
        episodes = episodes.loc[~probe]
    cal = LoadedRun(loaded.path, loaded.config, loaded.instances, episodes=episodes, manifest=loaded.manifest)
    passes = []
    original = calibration._Run.commit

    def counted(self, *requests, **kwargs):
        passes.append(self.loaded is cal)
        return original(self, *requests, **kwargs)

    monkeypatch.setattr(calibration._Run, "commit", counted)
    got, rows = result(cal)
    assert got == expected
    pd.testing.assert_frame_equal(rows, expected_rows)
    assert sum(passes) == (1 if stored == "as run" else 2)
    # The gates search the margin under the stored rows' simultaneous t the same way.
    want = gates(runs["cal"], runs["test"], alpha=0.2, resamples=50, seed=5, chunk_instances=3)
    passes.clear()
    have = gates(cal, runs["test"], alpha=0.2, resamples=50, seed=5, chunk_instances=3)
    pd.testing.assert_frame_equal(have.summary, want.summary)
    pd.testing.assert_frame_equal(have.curves, want.curves)
    assert {k: have.info[k] for k in ("threshold", "gamma", "gamma_satisfied")} == \
        {k: want.info[k] for k in ("threshold", "gamma", "gamma_satisfied")}
    assert sum(passes) == (1 if stored == "as run" else 2)
