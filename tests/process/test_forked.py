"""Helper processes forked at a command's start (``process.forked``, a ``ProcessPoolExecutor``): a job's
result is what its function returned, its exception raised in the caller; without helpers, or when one has
gone, the same call runs in the calling process; the helpers have imported what they were told to, and are
gone when the block ends: at once, without waiting for a running job, when the block raised (a failed job,
Ctrl-C)."""

import multiprocessing
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import probecommit.process.forked as forked
from probecommit.process.forked import forked_helpers

needs_fork = pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="no fork here")
SRC = Path(__file__).resolve().parents[2] / "src"


@pytest.fixture
def fork_allowed(monkeypatch):
    """Helpers forked even from the test process (pytest's workers may hold a thread of their own)."""
    monkeypatch.setattr(forked, "can_fork", lambda: True)


def _echo(value, *, twice=False):
    return (value, value) if twice else value


def _raise(message):
    raise ValueError(message)


def _die_in_helper(parent):
    if os.getpid() != parent:
        os._exit(1)
    return "here"


def _imported(name):
    return name in sys.modules


def _gone(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@needs_fork
def test_jobs_run_in_helpers_and_the_helpers_leave(fork_allowed):
    with forked_helpers(2) as helpers:
        assert helpers.count == 2
        echoes = [helpers.submit(_echo, i, twice=i % 2 == 1) for i in range(5)]
        pids = [helpers.submit(os.getpid) for _ in range(4)]
        assert [job.result() for job in echoes] == [0, (1, 1), 2, (3, 3), 4]
        pids = {job.result() for job in pids}
    assert os.getpid() not in pids
    assert all(_gone(pid) for pid in pids)  # joined: nothing left running


@needs_fork
def test_an_error_is_raised_in_the_caller_and_the_helper_goes_on(fork_allowed):
    with forked_helpers(1) as helpers:
        failing = helpers.submit(_raise, "planted")
        after = helpers.submit(_echo, "next")
        with pytest.raises(ValueError, match="planted"):
            failing.result()
        assert after.result() == "next"


@needs_fork
def test_a_failed_job_ends_the_block_without_waiting_for_a_running_one(fork_allowed):
    started = time.monotonic()
    with pytest.raises(ValueError, match="planted"):
        with forked_helpers(2) as helpers:
            pids = [helpers.submit(os.getpid).result()]
            helpers.submit(time.sleep, 60)
            helpers.submit(_raise, "planted").result()
    assert time.monotonic() - started < 20
    assert all(_gone(pid) for pid in pids)


@needs_fork
def test_a_helper_that_went_away_leaves_its_jobs_to_the_caller(fork_allowed):
    with forked_helpers(1) as helpers:
        gone = helpers.submit(_die_in_helper, os.getpid())
        assert gone.result() == "here"
        assert helpers.submit(os.getpid).result() == os.getpid()


@needs_fork
def test_helpers_import_what_they_were_told(fork_allowed, tmp_path, monkeypatch):
    (tmp_path / "pc_forked_warm_probe.py").write_text("VALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with forked_helpers(2, warm=("pc_forked_warm_probe", "no_such_module_here")) as helpers:
        jobs = [helpers.submit(_imported, "pc_forked_warm_probe") for _ in range(4)]
        assert [job.result() for job in jobs] == [True] * 4  # each helper imported it before its first job
    assert "pc_forked_warm_probe" not in sys.modules  # imported there, not here


def test_without_fork_every_job_runs_here(monkeypatch):
    monkeypatch.setattr(forked, "can_fork", lambda: False)
    with forked_helpers(2) as helpers:
        assert helpers.count == 0
        assert helpers.submit(os.getpid).result() == os.getpid()
        with pytest.raises(ValueError, match="here too"):
            helpers.submit(_raise, "here too").result()


_INTERRUPTED = """
    import os, signal, sys, time
    from probecommit.process.forked import forked_helpers
    signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal (see the test's docstring)
    with forked_helpers(2) as helpers:
        pids = {helpers.submit(os.getpid).result() for _ in range(8)}
        helpers.submit(time.sleep, 60)
        print(*pids, flush=True)
        helpers.submit(time.sleep, 60).result()
"""


@needs_fork
@pytest.mark.parametrize("group", [False, True], ids=["the command", "the terminal's process group"])
def test_ctrl_c_ends_the_command_and_its_helpers_at_once(group):
    """Ctrl-C while the command waits for a job: it ends (KeyboardInterrupt) without waiting for the
    helpers' running jobs, and the helpers are gone; sent to the command alone, or to its whole group.
    The child restores Python's Ctrl-C handler first: a test run started in the background by a
    non-interactive shell (a CI job) passes SIGINT on ignored, and Python then installs none."""
    child = subprocess.Popen([sys.executable, "-c", textwrap.dedent(_INTERRUPTED)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(SRC)},
                             start_new_session=True)
    try:
        pids = [int(pid) for pid in child.stdout.readline().split()]
        assert pids, child.stderr.read()
        started = time.monotonic()
        os.killpg(child.pid, signal.SIGINT) if group else child.send_signal(signal.SIGINT)
        _, errors = child.communicate(timeout=30)
    finally:
        child.kill()
    assert time.monotonic() - started < 20
    assert "KeyboardInterrupt" in errors and errors.count("Traceback") == 1  # the command's, none from a helper
    assert all(_gone(pid) for pid in pids)
