"""Trust the session log, by class (issue 38 items 3, 4, 5, 12, 16, 18, 19).

Every variant of a malformed or tampered log is refused with one line naming the file,
the line and the field (never a traceback, never a silently changed number); a Session's
write is all or nothing; the lock holds however its side file is meddled with.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import shutil

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from probecommit.robot import Session, SessionLocked, SessionLogError, load_session
from probecommit.robot.replay import replay_session
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import session_episodes
from probecommit.runner.config import config_data, parse_config
from tests.robot.conftest import RIG_SMALL


@pytest.fixture(scope="module")
def base_log(tmp_path_factory):
    """A complete small rig session (12 episodes, 4 positions with truths)."""
    return simulate_session(tmp_path_factory.mktemp("base") / "s", parse_config(RIG_SMALL))


def records(log):
    return [json.loads(line) for line in log.read_text().splitlines()]


def write(path, recs):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(json.dumps(r, separators=(",", ":")) + "\n" for r in recs))
    return path


def first(recs, kind, episode=None):
    return next(i for i, r in enumerate(recs) if r["type"] == kind and (episode is None or r.get("episode") == episode))


# ----------------------------------------------------------------------------- item 3: the state machine on read


def without_j(recs):
    """Records as a user's own tool might write them (the optional ``j`` numbering left out)."""
    return [{k: v for k, v in r.items() if k != "j"} for r in recs]


def test_an_observe_after_the_decision_is_refused(tmp_path, base_log):
    recs = without_j(records(base_log))
    ep = next(r["episode"] for r in recs if r["type"] == "episode" and r["taps"] == 2)
    obs = recs.pop(first(recs, "observe", ep))
    recs.insert(first(recs, "decide", ep) + 1, obs)
    with pytest.raises(SessionLogError, match=r"line \d+: .*(after episode|decide record with k)"):
        load_session(write(tmp_path / "a.jsonl", recs))


def test_an_extra_observe_is_refused(tmp_path, base_log):
    recs = without_j(records(base_log))
    i = first(recs, "observe", 0)
    recs.insert(i + 1, dict(recs[i]))
    with pytest.raises(SessionLogError, match=r"more observe records than its|observe record numbered"):
        load_session(write(tmp_path / "a.jsonl", recs))


def test_a_repeated_episode_number_is_refused(tmp_path, base_log):
    recs = records(base_log)
    start = first(recs, "episode", 1)
    end = first(recs, "episode", 2)
    recs[end:end] = [dict(r) for r in recs[start:end] if r.get("episode") == 1]  # episode 1 again
    with pytest.raises(SessionLogError, match="repeated or skipped"):
        load_session(write(tmp_path / "a.jsonl", recs))


@pytest.mark.parametrize("field, value, message", [
    ("retained_lo", 1e3, "retained_lo .* > retained_hi"),
    ("predicted", 7.5, "not a failure fraction"),
    ("predicted", -0.1, "predicted' must be a finite number >= 0"),
    ("action", [123.456], "is not action"),
])
def test_impossible_decide_values_are_refused(tmp_path, base_log, field, value, message):
    recs = records(base_log)
    recs[first(recs, "decide", 0)][field] = value
    with pytest.raises(SessionLogError, match=message):
        load_session(write(tmp_path / "a.jsonl", recs))


def test_a_header_naming_another_family_is_refused(tmp_path, base_log):
    recs = records(base_log)
    other = dict(RIG_SMALL, task="insertion", simulator={"engine": "analytic"})
    recs[0]["config"] = config_data(parse_config(other))
    with pytest.raises(SessionLogError, match="not on this family's probe grid"):
        load_session(write(tmp_path / "a.jsonl", recs))


# ----------------------------------------------------------------------------- items 5, 18: values and types


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_readings_are_refused_on_read(tmp_path, base_log, token):
    text = base_log.read_text().splitlines()
    i = next(n for n, line in enumerate(text) if '"type":"observe"' in line)
    rec = json.loads(text[i])
    text[i] = text[i].replace(f'"y":{json.dumps(rec["y"], separators=(",", ":"))}', f'"y":[{token}]')
    assert token in text[i]
    path = tmp_path / "a.jsonl"
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(SessionLogError, match=f"line {i + 1}: {token} is not a number"):
        replay_session(path)


def test_replay_compares_the_score_and_the_interval_not_only_the_action(tmp_path, base_log):
    recs = records(base_log)
    d = recs[first(recs, "decide", 0)]
    d["predicted"] = min(1.0, d["predicted"] + 0.01) if d["predicted"] < 1 else 0.5
    _, reproduced = replay_session(write(tmp_path / "a.jsonl", recs))
    assert reproduced == pytest.approx(11 / 12)
    from probecommit.robot.replay import same_decision

    assert same_decision(d, d) and not same_decision({**d, "retained_hi": d["retained_hi"] + 1}, d)


WRONG_TYPES = [
    ("episode", "episode", "0"), ("episode", "taps", "3"), ("observe", "u", "x"), ("observe", "y", [["1"]]),
    ("decide", "predicted", "0.5"), ("decide", "action_index", 1.5), ("outcome", "entered", "yes"),
    ("truth", "theta", None), ("decide", "hull_lo", True),
]


@pytest.mark.parametrize("kind, field, value", WRONG_TYPES)
def test_wrong_types_are_one_line_naming_line_and_field(tmp_path, base_log, kind, field, value):
    recs = records(base_log)
    i = first(recs, kind)
    recs[i][field] = value
    path = write(tmp_path / "a.jsonl", recs)
    with pytest.raises(SessionLogError, match=rf"line {i + 1}: {kind} record: field '{field}' must be"):
        load_session(path)
    from probecommit.cli.app import app

    result = CliRunner().invoke(app, ["audit", str(path)])
    assert result.exit_code == 2 and "Traceback" not in result.output and f"line {i + 1}" in result.output
    assert len(result.output.strip().splitlines()) == 1


# ----------------------------------------------------------------------------- item 4: all or nothing


def test_a_failed_write_is_never_written_later(tmp_path, rig_config):
    """A write that hits the file-size limit (a full disk) leaves the log as it was; the next record
    is the next line (the old buffered writer flushed the failed bytes with it)."""
    s = Session.open(tmp_path / "s", rig_config)
    try:
        s.start_episode("p0", taps=2)
        log = s.path
        size = log.stat().st_size
        old_handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        resource.setrlimit(resource.RLIMIT_FSIZE, (size + 20, hard))
        try:
            with pytest.raises(OSError) as info:
                s.observe(s.next_probe(), -3.0)
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
            signal.signal(signal.SIGXFSZ, old_handler)
        failed_size = log.stat().st_size
        s.observe(s.next_probe(), -3.0)
        s.observe(s.next_probe(), -2.0)
        s.decide()
    finally:
        s.close()
    obs = [r for r in records(log) if r["type"] == "observe"]
    assert [r["j"] for r in obs] == [1, 2]  # the failed record was not written with the next one
    _, episodes, _, _ = load_session(log)
    assert episodes[0].readings == [[-3.0], [-2.0]]
    assert failed_size == size  # truncated back at once
    assert str(log) in str(info.value) or info.value.filename == str(log)  # the error names the log


# ----------------------------------------------------------------------------- items 12, 16: the lock


def test_deleting_the_lock_file_does_not_let_a_second_writer_in(tmp_path, rig_config):
    with Session.open(tmp_path / "s", rig_config):
        (tmp_path / "s" / "session.jsonl.lock").unlink()
        with pytest.raises(SessionLocked):
            Session.open(tmp_path / "s")


def test_a_planted_lock_symlink_is_refused_and_its_target_untouched(tmp_path, rig_config):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    (tmp_path / "s").mkdir()
    os.symlink(victim, tmp_path / "s" / "session.jsonl.lock")
    with pytest.raises(SessionLogError, match="symbolic link"):
        Session.open(tmp_path / "s", rig_config)
    assert victim.read_text() == "precious\n"


def test_a_planted_log_symlink_is_refused(tmp_path, rig_config):
    victim = tmp_path / "victim.jsonl"
    victim.write_text("precious\n")
    (tmp_path / "s").mkdir()
    os.symlink(victim, tmp_path / "s" / "session.jsonl")
    with pytest.raises(SessionLogError, match="symbolic link"):
        Session.open(tmp_path / "s", rig_config)
    assert victim.read_text() == "precious\n"


# ----------------------------------------------------------------------------- item 19: the repair the message names


def test_the_cut_off_message_names_an_option_that_exists(tmp_path, rig_config):
    from probecommit.cli.app import app

    log = simulate_session(tmp_path / "s", rig_config, stop_after=2)
    with open(log, "ab") as handle:
        handle.write(b'{"type":"observe","episode":2')
    with pytest.raises(SessionLogError, match="probecommit robot simulate --repair"):
        Session.open(log)
    config = tmp_path / "rig.yaml"
    import yaml

    config.write_text(yaml.safe_dump(RIG_SMALL))
    result = CliRunner().invoke(app, ["robot", "simulate", str(config), "-o", str(tmp_path / "s"), "--repair"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "s" / "session.jsonl.partial").read_bytes().startswith(b'{"type":"observe"')
    assert len(load_session(log)[1]) == 12


# ----------------------------------------------------------------------------- the property-based suite

JSON_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-10**20, 10**20),
    st.floats(allow_nan=False, allow_infinity=False), st.sampled_from([1e308, -1e308, 7.5, -3.0, 0.5, 2.0]),
    st.text(max_size=5), st.lists(st.floats(-100, 100), max_size=3), st.lists(st.text(max_size=2), max_size=2),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
MUTATIONS = st.one_of(
    st.tuples(st.just("set"), st.integers(0, 10**6), st.integers(0, 10**6), JSON_VALUES),
    st.tuples(st.just("drop_field"), st.integers(0, 10**6), st.integers(0, 10**6), st.none()),
    st.tuples(st.just("swap"), st.integers(0, 10**6), st.integers(0, 10**6), st.none()),
    st.tuples(st.just("duplicate"), st.integers(0, 10**6), st.integers(0, 10**6), st.none()),
    st.tuples(st.just("delete"), st.integers(0, 10**6), st.integers(0, 10**6), st.none()),
    st.tuples(st.just("token"), st.integers(0, 10**6), st.integers(0, 10**6), st.sampled_from(["NaN", "Infinity", "1e999"])),
)


def mutate(recs, mutation):
    kind, a, b, value = mutation
    i, j = 1 + a % (len(recs) - 1), 1 + b % (len(recs) - 1)  # the header stays (its rules are tested above)
    text = None
    if kind in ("set", "drop_field", "token"):
        keys = [k for k in recs[i] if k != "type"]
        key = keys[b % len(keys)]
        if kind == "set":
            recs[i][key] = value
        elif kind == "drop_field":
            del recs[i][key]
        else:
            recs[i][key] = "@@TOKEN@@"
            text = "".join(json.dumps(r) + "\n" for r in recs).replace('"@@TOKEN@@"', value)
    elif kind == "swap":
        recs[i], recs[j] = recs[j], recs[i]
    elif kind == "duplicate":
        recs.insert(j, dict(recs[i]))
    else:
        del recs[i]
    return recs, text


def check_invariants(log):
    """What a log the reader accepts must satisfy (the Session's own write rules)."""
    _, episodes, truths, _ = load_session(log)
    numbers = sorted(episodes)
    assert numbers == list(range(len(numbers)))
    for ep in episodes.values():
        assert len(ep.probes) == len(ep.readings) <= ep.taps
        if ep.decision is not None:
            assert len(ep.probes) == ep.taps
            assert ep.decision["retained_lo"] <= ep.decision["retained_hi"]
            assert 0.0 <= ep.decision["predicted"] <= 1.0
        if ep.outcome is not None:
            assert ep.decision is not None
    try:
        rows = session_episodes(log).rows
    except SessionLogError:
        return
    assert (rows["covered"] == ((rows["retained_lo"] <= rows["z_true"]) & (rows["z_true"] <= rows["retained_hi"]))).all()
    assert rows["realized"].isin([0.0, 1.0]).all()


@given(mutations=st.lists(MUTATIONS, min_size=1, max_size=3))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_mutated_log_is_refused_in_one_line_or_read_consistently(tmp_path_factory, base_log, mutations):
    recs = records(base_log)
    text = None
    for mutation in mutations:
        if text is not None:
            break
        recs, text = mutate(recs, mutation)
    folder = tmp_path_factory.mktemp("m")
    path = folder / "session.jsonl"
    if text is None:
        write(path, recs)
    else:
        path.write_text(text)
    try:
        check_invariants(path)
    except SessionLogError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)
    shutil.rmtree(folder)
