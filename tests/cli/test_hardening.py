"""Bad input from data, paths and the environment: one line, no traceback, nothing silent."""

from __future__ import annotations

import time

import pandas as pd
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.cli.common import safe
from probecommit.runner.config import ConfigError, load_config

runner = CliRunner()
GOOD = {"name": "h", "repeats": 1, "instances": {"split": "h", "count": 2}, "probes": {"budget": 2},
        "belief": {"particles": 32}, "simulator": {"engine": "analytic"}, "blind_prior_samples": 200}


def test_an_unreachable_ray_address_fails_within_seconds(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(GOOD))
    start = time.perf_counter()
    result = runner.invoke(app, ["run", "s.yaml", "--ray", "127.0.0.1:1"])
    assert result.exit_code == 2 and "cannot reach the Ray cluster at 127.0.0.1:1" in " ".join(result.output.split())
    assert time.perf_counter() - start < 10 and not (tmp_path / "runs").exists()


@given(st.lists(st.sampled_from(list("[]/=bold link\x1b\x07ab:;") + ["[/bold]", "[link=x]", "\x1b[31m", "[red]"]),
                max_size=12).map("".join))
@settings(max_examples=60, deadline=None)
def test_markup_and_control_characters_from_data_are_inert(text):
    from probecommit.cli.common import SafeConsole

    console = SafeConsole(record=True, width=200)
    console.print(f"value: {text}")  # must never raise or render markup, escaped or not
    console.print(f"value: {safe(text)}")
    out = console.export_text()
    assert "\x1b" not in out and "\x07" not in out


def test_a_method_named_like_markup_and_a_formula_cell(tmp_path, monkeypatch):
    from tests.audit.test_io import ROBOT

    log = pd.read_csv(ROBOT)
    log["method"] = "=cmd|' /C calc'!A0"
    path = tmp_path / "q[b][bold].csv"
    log.to_csv(path, index=False)
    result = runner.invoke(app, ["audit", str(path), "--resamples", "100"])
    assert result.exit_code == 0, result.output
    assert "q[b][bold]" in " ".join(result.output.split())  # the path printed literally, not as markup
    cells = (tmp_path / "q[b][bold]-audit" / "audit.csv").read_text()
    assert "'=cmd" in cells and ",=cmd" not in cells and "\n=cmd" not in cells


def test_os_errors_are_one_line_naming_the_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(GOOD))
    (tmp_path / "taken").write_text("a file")
    result = runner.invoke(app, ["run", "s.yaml", "-o", "taken"])
    assert result.exit_code == 2 and "taken" in result.output and "Traceback" not in result.output
    long = "x" * 300
    result = runner.invoke(app, ["run", "s.yaml", "-o", long])
    assert result.exit_code == 2 and "name is too long" in result.output


def test_a_yaml_alias_bomb_is_refused_quickly(tmp_path):
    lines = ['a0: &a0 ["x", "x", "x", "x", "x", "x", "x", "x", "x"]']
    for i in range(1, 9):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    bomb = "\n".join(lines) + "\nname: *a8\n"
    path = tmp_path / "bomb.yaml"
    path.write_text(bomb)
    # CPU time, what a bomb costs (the wall clock also counts the tests of another xdist worker)
    start = time.process_time()
    with pytest.raises(ConfigError):
        load_config(path)
    assert time.process_time() - start < 2.0


def test_particles_as_an_integral_float_and_a_directory_path(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump({**GOOD, "belief": {"particles": 1e3}}))
    assert load_config(path).belief.particles == 1000
    with pytest.raises(ConfigError, match="is a directory"):
        load_config(tmp_path)


def test_a_probe_off_the_family_range_is_a_config_error(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump({**GOOD, "probes": {"schedule": [-9.0, 1000.0], "budget": 2}}))
    with pytest.raises(ConfigError, match=r"probe 1 = \[1000.0\] is outside the insertion family's probe range"):
        load_config(path)


def test_a_belief_that_loses_every_particle_is_reported(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = {**GOOD, "model": {"sigma": 1e-300}, "probes": {"budget": 3}}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(cfg))
    result = runner.invoke(app, ["run", "s.yaml"])
    assert result.exit_code == 0, result.output
    assert "lost every particle" in " ".join(result.output.split())
    episodes = pd.read_parquet(tmp_path / "runs" / "h" / "episodes.parquet")
    assert episodes["belief_resets"].max() > 0


def test_huge_configs_and_resamples_are_refused_with_an_estimate(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = {**GOOD, "belief": {"particles": 1_000_000}, "repeats": 1000}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(cfg))
    result = runner.invoke(app, ["run", "s.yaml"])
    assert result.exit_code == 2 and "GiB" in result.output and "belief.particles" in " ".join(result.output.split())
    assert not (tmp_path / "runs").exists()
    from probecommit.audit.stats import resample_counts

    with pytest.raises(MemoryError, match="--resamples"):
        resample_counts(1_000_000, 100_000_000)


def test_a_semicolon_csv_and_a_nan_boundary_offset_get_plain_errors(tmp_path):
    from tests.audit.test_io import ROBOT

    path = tmp_path / "semi.csv"
    pd.read_csv(ROBOT).to_csv(path, sep=";", decimal=",", index=False)
    result = runner.invoke(app, ["audit", str(path)])
    assert result.exit_code == 2 and "semicolon-separated" in " ".join(result.output.split())
    result = runner.invoke(app, ["scan", "--engine", "analytic", "--boundary-offset", "nan", "-o", str(tmp_path / "s")])
    assert result.exit_code == 2 and "boundary_offset" in result.output and "http" not in result.output


@given(st.integers(2, 7), st.integers(2, 12))
@settings(max_examples=15, deadline=None)
def test_generated_alias_bombs_never_take_long(depth, width):
    import tempfile
    from pathlib import Path

    lines = ['a0: &a0 ["x", "x"]']
    for i in range(1, depth):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]")
    text = "\n".join(lines) + f"\nname: *a{depth - 1}\n"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bomb.yaml"
        path.write_text(text)
        # CPU time, what a bomb costs (the wall clock also counts the tests of another xdist worker)
        start = time.process_time()
        with pytest.raises(ConfigError):
            load_config(path)
        assert time.process_time() - start < 2.0


def test_audit_intervals_are_whole_in_a_pipe(tmp_path):
    from tests.audit.test_io import ROBOT

    result = runner.invoke(app, ["audit", str(ROBOT), "--resamples", "100", "-o", str(tmp_path / "a")])
    assert result.exit_code == 0, result.output
    # every interval of the audit table on one line: "[lo, hi]" never split across lines
    assert all(line.count("[") == line.count("]") for line in result.output.splitlines())
