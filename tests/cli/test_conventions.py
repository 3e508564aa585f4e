"""The habits of the field: --version, completion, flags in help, logging, internal errors,
``run KEY=VALUE`` overrides and ``--sweep``, ``runs`` and ``runs compare``."""

from __future__ import annotations

import logging
import subprocess
import sys

import pandas as pd
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import probecommit
from probecommit.cli.app import app

runner = CliRunner()

GOOD = {
    "name": "conv",
    "seed": 1,
    "repeats": 2,
    "instances": {"split": "cli", "count": 3},
    "probes": {"budget": 2},
    "belief": {"particles": 32},
    "simulator": {"engine": "analytic"},
    "blind_prior_samples": 200,
}


def one_error_line(result) -> str:
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return lines[0]


@pytest.fixture
def study(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(GOOD))
    return path


# ----------------------------------------------------------------------------- 1. version, completion, help


def test_version_names_the_package_the_code_and_every_engine():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == f"probecommit {probecommit.__version__}"
    assert lines[1].startswith(("code: git ", "code: package source sha256 "))
    for engine in ("mujoco", "pybullet", "sapien", "ray", "numba"):
        assert engine in lines[3]


def test_shell_completion_is_offered(monkeypatch):
    """With shellingham installed, typer detects the shell from the process's ancestors and ignores the
    argument; a test run whose ancestors hold no shell (a detached background job) would find none and
    exit 1, so the detected shell is bash here."""
    import typer.completion

    monkeypatch.setattr(typer.completion, "_get_shell_name", lambda: "bash")
    result = runner.invoke(app, ["--help"])
    assert "--install-completion" in result.stdout and "--show-completion" in result.stdout
    script = runner.invoke(app, ["--show-completion", "bash"], prog_name="probecommit")
    assert script.exit_code == 0, (script.output, repr(script.exception))
    assert "complete -o default -F _probecommit_completion probecommit" in script.stdout


def _commands(group, prefix=()):
    import typer.main

    click_group = typer.main.get_command(group) if not hasattr(group, "commands") else group
    for name, command in click_group.commands.items():
        yield (*prefix, name)
        if hasattr(command, "commands"):
            yield from _commands(command, (*prefix, name))


def test_no_help_page_shows_a_flag_as_taking_a_value():
    names = list(_commands(app))
    assert ("runs",) in names and ("engines", "check") in names
    for args in [(), *names]:
        result = runner.invoke(app, [*args, "--help"], terminal_width=200)
        assert result.exit_code == 0, (args, result.output)
        assert "<bool>" not in result.stdout, args
    # ... and options that take a value still show their type.
    assert "<path>" in runner.invoke(app, ["run", "--help"], terminal_width=200).stdout


# ----------------------------------------------------------------------------- 2. logging and errors


def test_the_library_logs_nothing_unless_its_user_asks():
    code = ("import logging, probecommit\n"
            "assert any(isinstance(h, logging.NullHandler) for h in logging.getLogger('probecommit').handlers)\n"
            "logging.getLogger('probecommit.runner.study').warning('should not reach stderr')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""


def test_verbose_logs_progress_to_stderr(study):
    result = runner.invoke(app, ["-v", "run", str(study)])
    assert result.exit_code == 0, result.output
    assert "INFO probecommit.runner.study: runs/conv: 1 of 1 units to run" in result.stderr
    quiet = runner.invoke(app, ["run", str(study)])
    assert "INFO" not in quiet.stderr
    logging.getLogger("probecommit").setLevel(logging.WARNING)


def _boom(*args, **kwargs):
    raise ValueError("an invariant broke inside probecommit")


def test_an_internal_error_is_not_a_user_error(study, monkeypatch):
    import probecommit.runner.study

    monkeypatch.setattr(probecommit.runner.study, "preflight", _boom)
    result = runner.invoke(app, ["run", str(study)])
    assert result.exit_code == 1
    first, *rest = result.stderr.strip().splitlines()
    assert first == "error: internal error (ValueError): an invariant broke inside probecommit"
    assert "rerun with --debug" in " ".join(rest) and "Traceback" not in result.stderr
    result = runner.invoke(app, ["--debug", "run", str(study)])
    assert result.exit_code == 1
    assert "Traceback (most recent call last)" in result.stderr and "in _boom" in result.stderr
    assert "This is a bug in probecommit. Please report it to" in result.stderr


def test_a_user_error_stays_one_line_with_exit_2(study):
    result = runner.invoke(app, ["run", str(study), "belief.particles=-1"])
    assert result.exit_code == 2
    assert "invalid config field 'belief.particles'" in one_error_line(result)


def test_user_error_classes_keep_their_builtin_bases():
    from probecommit.audit.io import EpisodeTableError
    from probecommit.errors import UserError
    from probecommit.runner.config import ConfigError
    from probecommit.store.rundir import RunDirError

    assert issubclass(ConfigError, ValueError) and issubclass(ConfigError, UserError)
    assert issubclass(EpisodeTableError, ValueError) and issubclass(EpisodeTableError, UserError)
    assert issubclass(RunDirError, RuntimeError) and issubclass(RunDirError, UserError)


# ----------------------------------------------------------------------------- 3. overrides and sweeps


def test_overrides_give_the_run_an_edited_file_would(study, tmp_path):
    result = runner.invoke(app, ["run", str(study), "instances.count=2", "belief.particles=64", "-o", "over"])
    assert result.exit_code == 0, result.output
    edited = {**GOOD, "instances": {"split": "cli", "count": 2}, "belief": {"particles": 64}}
    (tmp_path / "edited.yaml").write_text(yaml.safe_dump(edited))
    assert runner.invoke(app, ["run", "edited.yaml", "-o", "edited"]).exit_code == 0
    assert (tmp_path / "over/config.yaml").read_text() == (tmp_path / "edited/config.yaml").read_text()
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "over/episodes.parquet"),
                                  pd.read_parquet(tmp_path / "edited/episodes.parquet"))
    recorded = yaml.safe_load((tmp_path / "over/overrides.yaml").read_text())
    assert recorded == {"config_file": str(study), "overrides": ["instances.count=2", "belief.particles=64"]}
    assert not (tmp_path / "edited/overrides.yaml").exists()


@pytest.mark.parametrize("args,expected", [
    (["belief.particle=64"], "invalid config field 'belief.particle': Extra inputs are not permitted"),
    (["model.sigma=abc"], "invalid config field 'model.sigma'"),
    (["belief.particles"], "an override is KEY=VALUE"),
    (["seed.x=1"], "override seed.x: seed is a value, not a section"),
    (["--sweep", "seed=1,,2"], "--sweep is KEY=A,B,C"),
    (["--sweep", "seed=1,1"], "lists a value more than once"),
    (["--sweep", "seed=1,2", "--sweep", "seed=3"], "--sweep names a key twice: seed"),
])
def test_bad_overrides_are_one_line_and_run_nothing(study, tmp_path, args, expected):
    result = runner.invoke(app, ["run", str(study), *args])
    assert result.exit_code == 2, result.output
    assert expected in one_error_line(result)
    assert not (tmp_path / "runs").exists()


def test_a_sweep_runs_one_directory_per_point_and_summarizes(study, tmp_path):
    result = runner.invoke(app, ["run", str(study), "--sweep", "belief.nu=0.5,0.9", "-m", "seed=1,2"],
                           terminal_width=200)
    assert result.exit_code == 0, result.output
    root = tmp_path / "runs/conv-sweep"
    dirs = sorted(p.name for p in root.iterdir() if p.is_dir())
    assert dirs == ["belief.nu=0.5,seed=1", "belief.nu=0.5,seed=2", "belief.nu=0.9,seed=1", "belief.nu=0.9,seed=2"]
    for name in dirs:
        config = yaml.safe_load((root / name / "config.yaml").read_text())
        nu, seed = name.split(",")
        assert config["belief"]["nu"] == float(nu.split("=")[1]) and config["seed"] == int(seed.split("=")[1])
        assert yaml.safe_load((root / name / "overrides.yaml").read_text())["sweep"] == [nu, seed]
    summary = pd.read_csv(root / "sweep.csv")
    assert summary["point"].tolist() == [d.replace(",", " ") for d in dirs]
    # The summary's numbers are each run's own: probe_robust at its last budget.
    episodes = pd.read_parquet(root / dirs[0] / "episodes.parquet")
    last = episodes[(episodes.method == "probe_robust") & (episodes.k == 2)]
    assert summary["failure"].iloc[0] == pytest.approx(last["realized"].mean(), abs=1e-12)
    assert "sweep: 4 runs" in result.stdout


@settings(max_examples=60, deadline=None)
@given(st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=False, allow_infinity=False, width=32),
                 st.booleans(), st.text(alphabet="abcxyz_-", min_size=1, max_size=8),
                 st.lists(st.integers(-5, 5), max_size=4)))
def test_an_override_reads_back_its_own_value(value):
    from probecommit.runner.overrides import format_override, parse_override

    assert parse_override(format_override(("model.sigma", value))) == ("model.sigma", value)


# ----------------------------------------------------------------------------- 4. runs, runs compare


@pytest.fixture
def three_runs(study, tmp_path):
    for args in (["-o", "runs/a"], ["-o", "runs/b", "belief.nu=0.5"], ["-o", "runs/c", "instances.seed=9"]):
        assert runner.invoke(app, ["run", str(study), *args]).exit_code == 0
    unfinished = tmp_path / "runs/d"
    (unfinished / "shards").mkdir(parents=True)
    (unfinished / "config.yaml").write_text(yaml.safe_dump(GOOD))
    return tmp_path / "runs"


def test_runs_lists_every_run_with_its_headline(three_runs):
    from probecommit.report.runs import list_runs

    frame = list_runs(three_runs).set_index("run")
    assert [p.rsplit("/", 1)[-1] for p in frame.index] == ["a", "b", "c", "d"]
    a = frame.loc[str(three_runs / "a")]
    episodes = pd.read_parquet(three_runs / "a/episodes.parquet")
    last = episodes[(episodes.method == "probe_robust") & (episodes.k == 2)]
    assert a["failure"] == pytest.approx(last["realized"].mean(), abs=1e-12)
    assert a["coverage"] == pytest.approx(last["covered"].mean(), abs=1e-12)
    assert (a["task"], a["engine"], a["status"], a["episodes"]) == ("insertion", "analytic", "complete", len(episodes))
    assert frame.loc[str(three_runs / "b"), "overrides"] == "belief.nu=0.5"
    assert frame.loc[str(three_runs / "d"), "status"].startswith("incomplete")
    result = runner.invoke(app, ["runs"], terminal_width=200)
    assert result.exit_code == 0 and "complete" in result.stdout and "incomplete" in result.stdout


def test_runs_compare_pairs_runs_on_the_same_instances(three_runs):
    from probecommit.report.runs import compare_runs

    same = compare_runs(three_runs / "a", three_runs / "b", resamples=200)
    assert same.paired
    assert same.config.to_dict("records") == [{"field": "belief.nu", "a": 0.8, "b": 0.5}]
    ea = pd.read_parquet(three_runs / "a/episodes.parquet")
    eb = pd.read_parquet(three_runs / "b/episodes.parquet")
    row = same.metrics.set_index(["method", "k", "metric"]).loc[("probe_robust", 2, "failure")]
    pick = lambda e: e[(e.method == "probe_robust") & (e.k == 2)]["realized"].mean()  # noqa: E731
    assert row["diff"] == pytest.approx(pick(eb) - pick(ea), abs=1e-12)
    assert row["lo"] <= row["diff"] <= row["hi"] and row["pairs"] == 6
    itself = compare_runs(three_runs / "a", three_runs / "a", resamples=200)
    assert itself.config.empty and (itself.metrics[["diff", "lo", "hi"]].abs().to_numpy() == 0).all()
    other = compare_runs(three_runs / "a", three_runs / "c", resamples=200)
    assert not other.paired and other.metrics["lo"].isna().all()
    result = runner.invoke(app, ["runs", "compare", str(three_runs / "a"), str(three_runs / "b")], terminal_width=200)
    assert result.exit_code == 0 and "paired: same instances" in result.stdout and "belief.nu" in result.stdout


def test_runs_compare_refuses_an_unfinished_run_in_one_line(three_runs):
    result = runner.invoke(app, ["runs", "compare", str(three_runs / "a"), str(three_runs / "d")])
    assert result.exit_code == 2 and "is not a complete run directory" in one_error_line(result)
    result = runner.invoke(app, ["runs", "compare", str(three_runs / "a")])
    assert result.exit_code == 2 and "two run directories" in one_error_line(result)
