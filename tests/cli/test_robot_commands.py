"""The robot workflow as a user runs it: simulate, show, audit (Table VII), replay under faults."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from probecommit.cli.app import app
from tests.robot.conftest import RIG_SMALL

runner = CliRunner()


def test_simulate_audit_and_replay_a_session(tmp_path):
    config = tmp_path / "rig.yaml"
    config.write_text(yaml.safe_dump(RIG_SMALL))
    out = tmp_path / "session"
    res = runner.invoke(app, ["robot", "simulate", str(config), "-o", str(out), "--stop-after", "5"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["robot", "show", str(out)])
    assert "5 episode(s)" in res.output and "no truth yet" in res.output
    assert runner.invoke(app, ["robot", "simulate", str(config), "-o", str(out)]).exit_code == 0  # resumes
    res = runner.invoke(app, ["audit", str(out), "--resamples", "200"])
    assert res.exit_code == 0, res.output
    audited = tmp_path / "session-audit"  # <input>-audit/ beside the input
    assert "coverage" in res.output and (audited / "robot_table.csv").is_file()
    assert (audited / "aim_error.png").is_file() and (audited / "aim_error.pdf").is_file()
    html = (audited / "audit.html").read_text()
    assert "realized Rₖ" in html and "fewer than 10" in html  # the robot audit writes HTML; few positions flagged
    res = runner.invoke(app, ["replay", str(out)])
    assert res.exit_code == 0 and "reproduced: 1.000" in res.output
    res = runner.invoke(app, ["replay", str(out / "session.jsonl"), "--fault", "boundary", "--sweep", "0:8:4",
                              "--resamples", "200"])
    assert res.exit_code == 0, res.output
    assert (out / "replay" / "fault_boundary.csv").is_file() and (out / "replay" / "fault_boundary.png").is_file()


def test_session_errors_are_one_line(tmp_path):
    res = runner.invoke(app, ["replay", str(tmp_path), "--fault", "boundary"])
    assert res.exit_code == 2 and "not one" in res.output
    bad = tmp_path / "x.jsonl"
    bad.write_text('{"type": "header", "format": "other"}\n')
    res = runner.invoke(app, ["audit", str(bad)])
    assert res.exit_code == 2 and "header format" in res.output


def test_replay_of_another_family_with_no_option_is_as_deployed(tmp_path):
    config = tmp_path / "hinge.yaml"
    config.write_text(yaml.safe_dump({
        "name": "h", "task": "hinge", "seed": 1, "repeats": 2,
        "instances": {"split": "t", "count": 2, "seed": 1, "contexts": [[1.0]]},
        "probes": {"schedule": "random", "budget": 2}, "belief": {"particles": 128},
        "simulator": {"engine": "analytic"}, "methods": ["probe_robust"]}))
    assert runner.invoke(app, ["run", str(config), "-o", str(tmp_path / "run")]).exit_code == 0
    res = runner.invoke(app, ["replay", str(tmp_path / "run"), "-o", str(tmp_path / "again")])
    assert res.exit_code == 0, res.output
    import pandas as pd

    a = pd.read_parquet(tmp_path / "run" / "episodes.parquet")
    b = pd.read_parquet(tmp_path / "again" / "episodes.parquet")
    pd.testing.assert_frame_equal(a.reset_index(drop=True), b.reset_index(drop=True))
    res = runner.invoke(app, ["replay", str(tmp_path / "run"), "--model", "corrected"])
    assert res.exit_code == 2 and "insertion shorthands" in res.output
