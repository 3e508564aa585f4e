"""The demo reads its own table to the user (three lines from the data) and names the next command, which works."""

from __future__ import annotations

import re

import pandas as pd
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.report.demo import explain_budget_table, next_command

runner = CliRunner()


def _table(rows):
    return pd.DataFrame(rows, columns=["method", "k", "episodes", "failure", "predicted", "optimism", "coverage",
                                       "escape", "failed"])


def test_three_lines_read_a_hand_table():
    table = _table([
        ("blind_bayes", 0, 64, 0.688, 0.826, -0.138, 1.0, 0.0, 0),
        ("blind_robust", 0, 64, 0.812, 0.805, 0.007, 1.0, 0.0, 0),
        ("probe_robust", 1, 64, 0.594, 0.585, 0.009, 0.922, 0.062, 0),
        ("probe_robust", 8, 64, 0.375, 0.092, 0.283, 0.656, 0.078, 0),
    ])
    assert explain_budget_table(table) == [
        "Optimism e_k (realized - predicted) rises from +0.009 to +0.283 over k = 1 to 8: Probe-Robust's predicted "
        "failure falls from 0.585 to 0.092, its realized failure falls from 0.594 to 0.375.",
        "Coverage (the truth inside the retained set) falls from 0.922 to 0.656, support escape (the truth outside "
        "every particle) rises from 0.062 to 0.078: more taps make the belief surer without keeping the truth in it.",
        "With no taps the blind executors fail Blind-Bayes 0.688, Blind-Robust 0.812; Probe-Robust at k = 8 fails 0.375.",
    ]


def test_a_table_that_does_not_degrade_is_not_told_that_it_does():
    table = _table([("probe_robust", 1, 8, 0.5, 0.5, 0.0, 0.9, 0.0, 0), ("probe_robust", 4, 8, 0.2, 0.25, -0.05, 1.0, 0.0, 0)])
    lines = explain_budget_table(table)
    assert len(lines) == 2  # no blind rows: no third line
    assert "optimism" not in lines[1] and lines[1].endswith("stays at 0.000.")
    assert "Optimism e_k (realized - predicted) falls from +0.000 to -0.050" in lines[0]


def test_next_command_names_the_other_tap_model():
    assert next_command("runs/demo", "deployed") == "probecommit replay runs/demo --model corrected"
    assert next_command("runs/x", "corrected") == "probecommit replay runs/x --model deployed"
    assert next_command("runs/x", "") is None


def test_the_demo_prints_its_reading_and_a_next_command_that_works(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["demo", "--engine", "analytic"], terminal_width=300)
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "Optimism e_k (realized - predicted)" in out and "Coverage (the truth inside the retained set)" in out
    command = re.search(r"next: (probecommit replay \S+ --model corrected)", out).group(1)
    assert command in (tmp_path / "runs/demo/report.md").read_text()
    replay = runner.invoke(app, command.split()[1:], terminal_width=300)
    assert replay.exit_code == 0, replay.output
    assert (tmp_path / "runs/demo-corrected/manifest.json").is_file()
    assert "probecommit runs compare runs/demo runs/demo-corrected" in replay.stdout


def test_the_readme_quickstart_is_the_two_commands_and_names_the_real_next_command():
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    quick = readme.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    block = quick.split("```bash\n", 1)[1].split("```", 1)[0]
    assert block.splitlines() == ["make demo", "make test"]
    assert f"`{next_command('runs/demo', 'deployed')}`" in quick
    # Internals live in docs/internals.md, not in the first thing a user reads.
    for internal in ("glibc", "MALLOC_", "mimalloc", "PROBECOMMIT_KERNELS", "about 15 s"):
        assert internal not in quick, internal
