"""Trust what the CLI prints and writes, by class (issue 38 items 16, 17, 18).

One console prints every text from data and paths literally (no markup, no emoji codes,
no control characters); one writer writes every user-visible file and never follows a
symlink it did not create; malformed options are one line, never a traceback.
"""

from __future__ import annotations

import os
import shutil

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from probecommit.cli.app import app
from tests.audit.test_io import ROBOT

runner = CliRunner()


def flat(text: str) -> str:
    return " ".join(text.split())


# ----------------------------------------------------------------------------- item 17: the safe console


def test_markup_emoji_and_escapes_in_paths_print_literally(tmp_path):
    folder = tmp_path / "d\x1b[31m[red][@click=(]"
    folder.mkdir()
    path = folder / "x:fire:y.csv"
    shutil.copy(ROBOT, path)
    result = runner.invoke(app, ["audit", str(path), "--resamples", "100"])
    assert result.exit_code == 0, result.output
    out = flat(result.output)
    assert "\x1b" not in result.output and "🔥" not in result.output
    assert "x:fire:y.csv" in out and "[red][@click=(]" in out and "d?[31m" in out


def test_a_session_title_prints_literally(tmp_path):
    from probecommit.robot.simulated import simulate_session
    from probecommit.runner.config import parse_config
    from tests.robot.conftest import RIG_SMALL

    log = simulate_session(tmp_path / "[red]s:fire:\x07", parse_config(RIG_SMALL))
    result = runner.invoke(app, ["replay", str(log.parent), "--resamples", "100"])
    assert result.exit_code == 0, result.output
    assert "[red]s:fire:?" in flat(result.output) and "\x07" not in result.output


@given(st.lists(st.sampled_from(list("ab[]/=@:();!x ") + ["[red]", "[/]", "[@click=(]", ":fire:", "\x1b[2J",
                                                        "\x07", "\x9b", "\u202e", "\r", "\x00"]), max_size=12).map("".join))
@settings(max_examples=50, deadline=None)
def test_any_text_prints_as_it_is_minus_control_characters(text):
    from probecommit.cli.common import SafeConsole, clean

    console = SafeConsole(record=True, width=500)
    console.print(text)
    console.print(text, "and", text)
    out = console.export_text()
    assert out.splitlines()[0].rstrip() == clean(text).rstrip()
    assert not any(c in out for c in "\x1b\x07\x9b\u202e\x00\r")


# ----------------------------------------------------------------------------- item 16: the safe writer


@pytest.mark.parametrize("name", ["audit.csv", "audit.html", "audit.png"])
def test_a_planted_output_symlink_is_refused_and_its_target_untouched(tmp_path, name):
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    log = tmp_path / "log.csv"
    shutil.copy(ROBOT, log)
    (tmp_path / "log-audit").mkdir()
    os.symlink(victim, tmp_path / "log-audit" / name)
    result = runner.invoke(app, ["audit", str(log), "--resamples", "100"])
    assert result.exit_code == 2 and "symbolic link" in result.output and "Traceback" not in result.output
    assert victim.read_text() == "precious\n"


def test_a_symlinked_default_output_folder_is_refused(tmp_path):
    from probecommit.store.safefile import UnsafePathError, output_dir

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    os.symlink(elsewhere, tmp_path / "calibration")
    with pytest.raises(UnsafePathError, match="output folder"):
        output_dir(None, tmp_path / "calibration")
    assert output_dir(tmp_path / "calibration", tmp_path / "x") == tmp_path / "calibration"  # the user's own choice


@given(name=st.sampled_from(["audit.csv", "audit.html", "table3.csv", "calibration.json", "gates.png", "x.parquet"]),
       planted=st.sampled_from([None, "file", "dir", "dangling"]), data=st.binary(max_size=64))
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_planted_link_is_never_followed(tmp_path_factory, name, planted, data):
    from probecommit.store.safefile import UnsafePathError, write_bytes

    root = tmp_path_factory.mktemp("w")
    victim = root / "victim"
    if planted == "dir":
        victim.mkdir()
    elif planted == "file":
        victim.write_bytes(b"precious")
    dest = root / "out" / name
    dest.parent.mkdir()
    if planted is not None:
        os.symlink(victim, dest)
        with pytest.raises(UnsafePathError):
            write_bytes(dest, data)
        assert dest.is_symlink()
        if planted == "file":
            assert victim.read_bytes() == b"precious"
        elif planted == "dangling":
            assert not victim.exists()
    else:
        write_bytes(dest, data)
        assert dest.read_bytes() == data and not dest.is_symlink()
    assert not [p for p in dest.parent.iterdir() if p.name.endswith(".tmp")]


# ----------------------------------------------------------------------------- item 18: malformed options


@pytest.mark.parametrize("value, message", [
    ("!!python/object/apply:os.system ['echo hi']", "could not determine a constructor"),
    ("[1, 2", "not valid YAML"),
    ("&a [*a]", "recursive"),
])
def test_a_bad_set_value_is_one_line(tmp_path, value, message):
    result = runner.invoke(app, ["replay", str(tmp_path / "run"), "--set", f"model.sigma={value}"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert message in flat(result.output) and "--set model.sigma" in flat(result.output)
    assert len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize("sweep", ["0:inf:1", "0:nan:1", "-inf:0:1", "0:1:inf"])
def test_a_non_finite_sweep_is_one_line(sweep):
    from probecommit.robot.replay import parse_sweep

    with pytest.raises(ValueError, match="--sweep must be"):
        parse_sweep(sweep)


@given(st.lists(st.sampled_from(list("0123456789.:,-e+ ") + ["inf", "nan", "1e999"]), max_size=10).map("".join))
@settings(max_examples=50, deadline=None)
def test_any_sweep_text_is_a_finite_list_or_one_value_error(text):
    from probecommit.robot.replay import parse_sweep

    try:
        values = parse_sweep(text)
    except ValueError as exc:
        assert "\n" not in str(exc)
        return
    assert 0 < len(values) <= 1000 and all(v == v and abs(v) != float("inf") for v in values)
