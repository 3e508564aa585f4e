"""The Session serves every family: per-episode contexts (a target), any family's probes and actions,
and the robot-log audit and replay of a family with a target (push1d)."""

from __future__ import annotations

import json
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

from probecommit.robot.replay import replay_session
from probecommit.robot.session import Session, SessionError
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import robot_table, session_episodes
from probecommit.tasks.push1d.model import stop_distance

EXAMPLE = str(Path(__file__).resolve().parents[2] / "examples" / "push_robot_loop.py")
PUSH = {"name": "p1", "task": "push1d", "seed": 3, "repeats": 1, "instances": {"count": 2, "contexts": [[0.8], [1.4]]},
        "probes": {"schedule": "random", "budget": 2, "budgets": [1, 2]}, "belief": {"particles": 256}}


def test_a_family_with_a_target_runs_audits_and_replays(tmp_path):
    log = simulate_session(tmp_path / "s", PUSH)
    records = [json.loads(line) for line in log.read_text().splitlines()]
    episodes = [r for r in records if r["type"] == "episode"]
    assert len(episodes) == 8 and {tuple(r["context"]) for r in episodes} == {(0.8,), (1.4,)}
    rows = session_episodes(log).rows
    assert len(rows) == 8 and rows["realized"].ge(0).all() and rows["covered"].dtype == bool
    # The realized miss is the model's at the recorded truth and context, by hand for the first episode.
    truths = {r["position"]: r["theta"] for r in records if r["type"] == "truth"}
    first = next(r for r in records if r["type"] == "decide")
    ep = episodes[first["episode"]]
    slid = float(stop_distance(first["action"][0], *truths[ep["position"]]))
    assert rows["realized"].iloc[0] == pytest.approx(abs(slid - ep["context"][0]), rel=1e-12)
    assert set(robot_table(rows, resamples=50)["taps"]) == {1, 2}
    _, reproduced = replay_session(log)
    assert reproduced == 1.0


def test_a_context_is_required_where_the_family_has_one_and_refused_where_not(tmp_path):
    with Session.open(tmp_path / "push", PUSH) as session:
        with pytest.raises(SessionError, match=r"needs a context of 1 finite number\(s\) \(target\)"):
            session.start_episode("a", taps=1)
        session.start_episode("a", taps=0, context=1.2)
        assert session.decide().action > 0
    with Session.open(tmp_path / "ins", {"task": "insertion", "instances": {"count": 2}}) as session:
        with pytest.raises(SessionError, match="has no context"):
            session.start_episode("a", taps=1, context=[1.0])


def test_the_push_example_loop_runs_and_resumes(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["push_robot_loop.py", str(tmp_path / "loop")])
    runpy.run_path(EXAMPLE, run_name="__main__")
    first = capsys.readouterr().out
    assert first.count("probe push(es)") == 6
    runpy.run_path(EXAMPLE, run_name="__main__")  # resumed: nothing left to do
    assert "probe push(es)" not in capsys.readouterr().out
    assert len(session_episodes(tmp_path / "loop").rows) == 6


_REGISTRY = __import__("probecommit.tasks.registry", fromlist=["families", "builtin_packages"])
#: The built-in families with an analytic engine (those a test or notebook registered are not collected).
ANALYTIC = sorted(name for name, spec in _REGISTRY.families().items()
                  if "analytic" in spec.engines and name in _REGISTRY.builtin_packages())


@pytest.mark.parametrize("family", ANALYTIC)
def test_every_family_runs_a_session_that_audits_and_replays_exactly(family, tmp_path):
    from probecommit.runner.family_check import _deep_merge
    from probecommit.tasks.registry import families

    spec = families()[family]
    data = _deep_merge({"name": "s", "task": family, "seed": 5, "repeats": 1, "instances": {"count": 2},
                        "probes": {"schedule": "random", "budget": 2, "budgets": [1, 2]}, "belief": {"particles": 128},
                        "simulator": {"engine": "analytic"}}, spec.example)
    log = simulate_session(tmp_path / "s", data)
    rows = session_episodes(log).rows
    n_contexts = len(data["instances"].get("contexts", [[]]))
    assert len(rows) == 2 * n_contexts * 2
    _, reproduced = replay_session(log)
    assert reproduced == 1.0


def test_the_cli_audits_and_replays_a_push_session_log(tmp_path):
    from typer.testing import CliRunner

    from probecommit.cli.app import app

    log = simulate_session(tmp_path / "s", PUSH)
    audited = CliRunner().invoke(app, ["audit", str(log.parent)])
    assert audited.exit_code == 0, audited.output
    # a session's audit goes beside it, <dir>-audit/ (the one output rule for every audited input)
    assert "coverage" in audited.output and (log.parent.with_name(f"{log.parent.name}-audit") / "robot_table.csv").is_file()
    replayed = CliRunner().invoke(app, ["replay", str(log.parent)])
    assert replayed.exit_code == 0 and "recorded decisions reproduced: 1.000" in replayed.output
