"""`probecommit run` on bad input: exit 2, one line on stderr, no run directory."""

import pytest
import yaml
from typer.testing import CliRunner

from probecommit.cli.app import app

GOOD = {
    "name": "clitest",
    "seed": 1,
    "repeats": 2,
    "instances": {"split": "cli", "count": 3},
    "probes": {"budget": 2},
    "belief": {"particles": 32},
    "simulator": {"engine": "analytic"},
    "blind_prior_samples": 200,
}


def invoke(tmp_path, monkeypatch, config, *extra):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "study.yaml"
    path.write_text(config if isinstance(config, str) else yaml.safe_dump(config))
    return CliRunner().invoke(app, ["run", str(path), *extra])


def error_line(result) -> str:
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return lines[0]


@pytest.mark.parametrize(
    "config,expected",
    [
        ({**GOOD, "belief": {"particles": -3}}, "invalid config field 'belief.particles': Input should be greater than or equal to 1"),
        ({**GOOD, "model": {"prior_low": [-10, 0.7], "prior_high": [-11, 1.3]}}, "invalid config field 'model.prior_high'"),
        ({**GOOD, "instances": {"split": "cli", "count": 3, "truth_low": [20, 0.7]}}, "invalid config field 'instances.truth_low'"),
        ({**GOOD, "methods": ["probe_robust", "probe_robust"]}, "invalid config field 'methods'"),
        ({**GOOD, "repeats": True}, "invalid config field 'repeats': expected a number"),
        ({**GOOD, "simulator": {"engine": "gazebo"}}, "task family 'insertion' has no 'gazebo' simulator; it has: analytic"),
        ({**GOOD, "task": "juggling"}, "unknown task family 'juggling'; registered: darts, grasp, hinge, insertion"),
        ("name: [x\n", "not valid YAML at line 2"),
        ("seed: 1\nseed: 2\n", "duplicate key 'seed'"),
    ],
)
def test_bad_config_exits_2_with_one_line_and_writes_nothing(tmp_path, monkeypatch, config, expected):
    result = invoke(tmp_path, monkeypatch, config, "--out", str(tmp_path / "out"))
    assert result.exit_code == 2, result.output
    assert expected in error_line(result)
    assert not (tmp_path / "out").exists()
    assert not (tmp_path / "runs").exists()
    # Without --out the default runs/<name> is not created either.
    result = CliRunner().invoke(app, ["run", str(tmp_path / "study.yaml")])
    assert result.exit_code == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study.yaml"]


def test_missing_config_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["run", "nope.yaml"])
    assert result.exit_code == 2
    assert "config file not found: nope.yaml" in error_line(result)


def test_run_directory_of_another_config_is_refused_in_one_line(tmp_path, monkeypatch):
    assert invoke(tmp_path, monkeypatch, GOOD).exit_code == 0
    assert (tmp_path / "runs" / "clitest" / "manifest.json").is_file()
    result = invoke(tmp_path, monkeypatch, {**GOOD, "seed": 2})
    assert result.exit_code == 2
    line = error_line(result)
    assert "holds a run of a different config (seed is 1 there, 2 here)" in line
    # The resumable run is untouched; the same command finishes (no-op) fine.
    assert invoke(tmp_path, monkeypatch, GOOD).exit_code == 0


def test_the_command_takes_arrow_buffers_from_the_c_allocator_unless_told_otherwise(monkeypatch):
    import os
    import subprocess
    import sys

    from probecommit.cli.app import ARROW_POOL_ENV, use_system_arrow_pool

    monkeypatch.delenv(ARROW_POOL_ENV, raising=False)
    use_system_arrow_pool()
    assert os.environ[ARROW_POOL_ENV] == "system"
    # pyarrow reads the variable when its pool is first used: a fresh process shows the effect.
    probe = "import pyarrow as pa; print(pa.default_memory_pool().backend_name)"
    assert subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          env=dict(os.environ)).stdout.strip() == "system"
    monkeypatch.setenv(ARROW_POOL_ENV, "jemalloc")  # the user's choice stands
    use_system_arrow_pool()
    assert os.environ[ARROW_POOL_ENV] == "jemalloc"


def test_threads_option_runs_units_in_threads_and_refuses_zero(tmp_path, monkeypatch):
    import json

    cfg = {**GOOD, "unit_instances": 1}
    done = invoke(tmp_path, monkeypatch, cfg, "--threads", "2", "-o", "threaded")
    assert done.exit_code == 0, done.output
    assert json.loads((tmp_path / "threaded" / "manifest.json").read_text())["backend"] == "threads:2"
    bad = CliRunner().invoke(app, ["run", str(tmp_path / "study.yaml"), "--threads", "0", "-o", "never"],
                             env={"COLUMNS": "200"})  # typer's usage error, in one box line at this width
    assert bad.exit_code == 2
    assert "Invalid value for '--threads' / '-t': Input should be greater than or equal to 1" in bad.stderr
    assert not (tmp_path / "never").exists()
