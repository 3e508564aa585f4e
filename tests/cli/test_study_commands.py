"""The study commands as a user runs them: scan, faults, reproduce (errors and outputs)."""

import json

import pandas as pd
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.runner.study import run_study

runner = CliRunner()


def test_every_study_command_has_help():
    for command in ("scan", "faults", "reproduce"):
        result = runner.invoke(app, [command, "--help"])
        assert result.exit_code == 0 and "Usage" in result.output


def test_scan_fits_a_planted_analytic_boundary(tmp_path):
    result = runner.invoke(app, ["scan", "--engine", "analytic", "--boundary-offset", "0.6", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "scan_summary.json").read_text())
    assert abs(summary["delta"] - 0.6) <= 1e-3 and summary["scans"] == 48
    assert (tmp_path / "scan_section.png").stat().st_size > 0


def test_scan_rejects_an_unknown_engine(tmp_path):
    result = runner.invoke(app, ["scan", "--engine", "gazebo", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "--engine must be one of analytic, mujoco, pybullet, sapien" in " ".join(result.output.split()) and "Traceback" not in result.output


def test_reproduce_rejects_an_unknown_target():
    result = runner.invoke(app, ["reproduce", "juggling"])
    assert result.exit_code == 2
    assert "unknown reproduce target 'juggling'" in " ".join(result.output.split())


def test_faults_on_a_base_run_skips_the_faults_needing_other_rollouts(tmp_path, make_config):
    cfg = make_config(model={"boundary": "corrected", "delta": 0.905}, probes={"budget": 3})
    base = run_study(cfg, tmp_path / "base").run_dir
    result = runner.invoke(app, ["faults", str(base), "--out", str(tmp_path / "faults")])
    assert result.exit_code == 0, result.output
    episodes = pd.read_parquet(tmp_path / "faults" / "faults_episodes.parquet")
    assert set(episodes.fault) == {"none", "boundary", "particles", "frame"}
    assert "noise" in result.output and "prior" in result.output  # named as skipped


def test_faults_on_a_missing_run_is_one_line(tmp_path):
    result = runner.invoke(app, ["faults", str(tmp_path / "nope")])
    assert result.exit_code == 2 and "Traceback" not in result.output


def test_engines_check_agrees_on_every_installed_engine():
    result = runner.invoke(app, ["engines", "check", "--engines", "mujoco,analytic"])
    assert result.exit_code == 0, result.output
    assert "tap over the plate" in result.output and "NO (" not in result.output


def test_scan_any_engine_with_capture(tmp_path):
    result = runner.invoke(app, ["scan", "--engine", "analytic", "--boundary-offset", "0.5", "--capture",
                                 "--step", "0.5", "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "delta = +0.50" in result.output and "capture window / w(c) = 1.0" in result.output
    assert (tmp_path / "capture.parquet").is_file()
    bad = runner.invoke(app, ["scan", "--engine", "gazebo"])
    assert bad.exit_code == 2 and "mujoco, pybullet, sapien" in bad.output
