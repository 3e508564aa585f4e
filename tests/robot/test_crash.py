"""A session killed with SIGKILL mid-run and reopened continues without loss."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from probecommit.robot.simulated import simulate_session
from probecommit.runner.config import parse_config
from tests.robot.conftest import RIG_SMALL

SCRIPT = textwrap.dedent("""
    import sys, time
    from probecommit.robot.simulated import simulate_session
    from probecommit.runner.config import parse_config
    from tests.robot.conftest import RIG_SMALL
    slow = lambda done, total: time.sleep(0.15)  # a slow robot: room to be killed mid-session
    simulate_session(sys.argv[1], parse_config(RIG_SMALL), progress=slow)
""")


def _decisions(path):
    out = []
    for line in path.read_text().splitlines():
        record = json.loads(line)
        if record["type"] in ("observe", "decide", "outcome", "truth", "episode"):
            out.append({k: v for k, v in record.items() if k not in ("t", "decide_s")})
    return out


@pytest.mark.slow
def test_sigkill_mid_session_then_resume_loses_nothing(tmp_path):
    log_dir = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, str(log_dir)], cwd=os.getcwd())
    log = log_dir / "session.jsonl"
    deadline = time.time() + 60
    while time.time() < deadline:
        if log.is_file() and log.read_text().count('"type":"outcome"') >= 4:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    before = [line for line in log.read_bytes().split(b"\n") if line]
    complete = log.read_text().count('"type":"outcome"')
    assert 4 <= complete < 12  # killed mid-session
    simulate_session(log_dir, parse_config(RIG_SMALL), repair=True)
    after = log.read_bytes().split(b"\n")
    # Every complete record written before the kill is still there, byte for byte, in order.
    kept = [line for line in before if line.endswith(b"}")]
    assert after[: len(kept)] == kept
    straight = simulate_session(tmp_path / "straight", parse_config(RIG_SMALL))
    assert _decisions(log) == _decisions(straight)
