"""Helper processes forked at a command's start (``process.forked``): a job's result is what its function
returned, in the job's own order, its exception raised in the caller; without helpers, or when one has
gone, the same call runs in the calling process; the helpers have imported what they were told to, and
are gone when the block ends."""

import multiprocessing
import os
import sys

import pytest

import probecommit.process.forked as forked
from probecommit.process.forked import forked_helpers

needs_fork = pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="no fork here")


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


@needs_fork
def test_jobs_run_in_helpers_in_their_order(fork_allowed):
    with forked_helpers(2) as helpers:
        assert helpers.count == 2
        pids = [helpers.submit(os.getpid), helpers.submit(os.getpid)]
        echoes = [helpers.submit(_echo, i, twice=i % 2 == 1) for i in range(5)]
        assert [job.result() for job in echoes] == [0, (1, 1), 2, (3, 3), 4]
        pids = [job.result() for job in pids]
        first = helpers.process
    assert os.getpid() not in pids and len(set(pids)) == 2  # the two first jobs went to one helper each
    assert first.pid in pids and first.exitcode == 0  # the helpers saw their pipes' end and left (none killed)
    for pid in pids:  # joined: nothing left running
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


@needs_fork
def test_an_error_is_raised_in_the_caller_and_the_helper_goes_on(fork_allowed):
    with forked_helpers(1) as helpers:
        failing = helpers.submit(_raise, "planted")
        after = helpers.submit(_echo, "next")
        with pytest.raises(ValueError, match="planted"):
            failing.result()
        assert after.result() == "next"


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
        jobs = [helpers.submit(_imported, "pc_forked_warm_probe") for _ in range(2)]
        assert [job.result() for job in jobs] == [True, True]  # the first imports, the second is forked from it
    assert "pc_forked_warm_probe" not in sys.modules  # imported there, not here


def test_without_fork_every_job_runs_here(monkeypatch):
    monkeypatch.setattr(forked, "can_fork", lambda: False)
    with forked_helpers(2) as helpers:
        assert helpers.count == 0
        assert helpers.submit(os.getpid).result() == os.getpid()
        with pytest.raises(ValueError, match="here too"):
            helpers.submit(_raise, "here too").result()
