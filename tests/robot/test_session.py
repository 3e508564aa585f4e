"""The online Session: the loop, its log, resuming, and bad input that loses nothing."""

from __future__ import annotations

import json

import numpy as np
import pytest

from probecommit.robot import Session, SessionError, SessionLocked, SessionLogError, load_session
from probecommit.robot.log import read_records
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import robot_table, session_episodes


def lines(path):
    return path.read_text().splitlines()


def test_simulated_session_writes_a_complete_log(tmp_path, rig_config):
    log = simulate_session(tmp_path / "s", rig_config)
    config, episodes, truths, _ = load_session(log)
    assert len(episodes) == 4 * 1 * 3 and all(ep.done for ep in episodes.values())
    assert sorted(len(ep.probes) for ep in episodes.values()) == sorted([1, 2, 3] * 4)
    assert len(truths) == 4
    rows = session_episodes(log).rows
    table = robot_table(rows, resamples=200)
    assert list(table["taps"]) == [1, 2, 3] and table["episodes"].sum() == 12
    assert table["in_window"].sum() == int((rows["realized"] == 0).sum())


def test_same_seed_same_log(tmp_path, rig_config):
    a = simulate_session(tmp_path / "a", rig_config)
    b = simulate_session(tmp_path / "b", rig_config)
    strip = lambda p: [{k: v for k, v in json.loads(l).items() if k not in ("t", "created", "decide_s")}  # noqa: E731
                       for l in lines(p)]
    assert strip(a) == strip(b)


def test_probes_come_from_the_schedule_not_the_belief(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        s.start_episode("p0", taps=3)
        planned = []
        while (u := s.next_probe()) is not None:
            planned.append(u)
            s.observe(u, 0.0)
        assert len(planned) == 3 and all(np.isclose(s.model.probe_grid[:, 0], u).any() for u in planned)
        d = s.decide()
        assert d.k == 3 and d.retained[0] <= d.retained[1] and d.hull[0] <= d.retained[0]
        assert 0.0 <= d.score <= 1.0 and d.seconds < 0.5
    # Episode 0 of another log with the same seed gets the same taps whatever it read.
    with Session.open(tmp_path / "t", rig_config) as s:
        s.start_episode("p0", taps=3)
        again = []
        while (u := s.next_probe()) is not None:
            again.append(u)
            s.observe(u, -10.0)
    assert again == planned


def test_resume_continues_an_open_episode_with_the_same_belief(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        s.start_episode("p0", taps=3)
        s.observe(s.next_probe(), 0.0)
    with Session.open(tmp_path / "s") as s:  # no config: the header's
        assert s.current.episode == 0 and len(s.current.probes) == 1
        while (u := s.next_probe()) is not None:
            s.observe(u, 0.0)
        resumed = s.decide()
    with Session.open(tmp_path / "u", rig_config) as s:
        s.start_episode("p0", taps=3)
        while (u := s.next_probe()) is not None:
            s.observe(u, 0.0)
        straight = s.decide()
    assert (resumed.action, resumed.score, resumed.retained) == (straight.action, straight.score, straight.retained)


def test_bad_readings_are_refused_and_recorded(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        s.start_episode("p0", taps=2)
        u = s.next_probe()
        with pytest.raises(SessionError, match="outside the physical range"):
            s.observe(u, -40.0)
        with pytest.raises(SessionError, match="finite"):
            s.observe(u, float("nan"))
        with pytest.raises(SessionError, match="not on the probe grid"):
            s.observe(1.234, 0.0)
        assert s.current.probes == []  # nothing assimilated
        with pytest.raises(SessionError, match="0 of its 2 taps"):
            s.decide()
        with pytest.raises(SessionError, match="still open"):
            s.start_episode("p1", taps=1)
    records, _ = read_records(tmp_path / "s")
    rejected = [r for r in records if r["type"] == "rejected"]
    assert [r["y"] for r in rejected] == [[-40.0], ["nan"], [0.0]]


def test_two_writers_are_refused_naming_the_holder(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config):
        with pytest.raises(SessionLocked, match=r"pid \d+"):
            Session.open(tmp_path / "s")
    Session.open(tmp_path / "s").close()  # released on close


def test_a_truncated_last_line_is_named_and_repair_keeps_its_bytes(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        s.start_episode("p0", taps=1)
    log = tmp_path / "s" / "session.jsonl"
    n = len(lines(log))
    with open(log, "ab") as f:
        f.write(b'{"type":"observe","episode":0,"u":[0.0],"y":[-1')
    with pytest.raises(SessionLogError, match=f"line {n + 1} was cut off"):
        Session.open(log)
    with Session.open(log, repair=True) as s:
        assert s.current.probes == []
    assert (tmp_path / "s" / "session.jsonl.partial").read_bytes().startswith(b'{"type":"observe"')
    assert len(lines(log)) == n


def test_a_corrupt_line_and_a_foreign_file_are_named(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        s.start_episode("p0", taps=1)
    log = tmp_path / "s" / "session.jsonl"
    text = lines(log)
    log.write_text("\n".join(text[:1] + ["not json"] + text[1:]) + "\n")
    with pytest.raises(SessionLogError, match="line 2 is not valid JSON"):
        load_session(log)
    other = tmp_path / "other.jsonl"
    other.write_text('{"a": 1}\n')
    with pytest.raises(SessionLogError, match="line 1 is not a session record"):
        load_session(other)


def test_a_changed_config_is_refused(tmp_path, rig_config):
    Session.open(tmp_path / "s", rig_config).close()
    changed = rig_config.model_copy(update={"seed": 99})
    with pytest.raises(SessionLogError, match="differs"):
        Session.open(tmp_path / "s", changed)


def test_missing_truths_are_named_not_scored(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config) as s:
        for position in ("p0", "p1"):
            s.start_episode(position, taps=1)
            s.observe(s.next_probe(), 0.0)
            s.decide()
            s.record_outcome(entered=True)
        s.record_truth("p0", [1.0, 1.0])
        with pytest.raises(SessionError, match="2 finite number"):
            s.record_truth("p1", [1.0])
    result = session_episodes(tmp_path / "s")
    assert len(result.rows) == 1
    assert any("no truth recorded for position 'p1'" in note for note in result.notes)


def test_the_audit_says_when_the_last_line_was_cut_off(tmp_path, rig_config):
    log = simulate_session(tmp_path / "s", rig_config)
    with open(log, "ab") as f:
        f.write(b'{"type":"episode","epis')
    result = session_episodes(log)
    assert len(result.rows) == 12 and any("cut off mid-write" in note for note in result.notes)
