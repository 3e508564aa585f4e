"""Helper processes forked when a command starts, that import what a later step needs while the
command works, and then run that step's parts beside each other.

``probecommit calibrate`` spends about 5 s in ``calibrate`` on two busy CPUs, then draws its
report: four figures (the calibration figure saved, then drawn again for the page; the audit
figure at two widths) and their PNGs, about 1.7 CPU s, after importing matplotlib (0.3 CPU s),
all on one thread while the second CPU waits (issue 42, target 3). Figures are Python bound (the
GIL), so threads would not overlap them; processes forked before the work begins do, and import
matplotlib while ``calibrate`` still runs. A job's result is what its function returns (pickled
back), so a figure drawn by a helper is the same bytes as one drawn here.

A helper is forked only from a process with one Python thread (the command before its work
starts) and where ``fork`` exists; otherwise, or when a helper has gone, a job runs in the calling
process when its result is asked for: the same function and arguments, so the same result.
"""

from __future__ import annotations

import contextlib
import importlib
import multiprocessing
import os
import signal
import threading
from collections import deque
from typing import Any, Callable, Iterator, Sequence


class _Job:
    """A submitted call: its result, once a helper sent it back or it ran here."""

    def __init__(self, helper: "_Helper | None", fn: Callable[..., Any], args: tuple, kwargs: dict) -> None:
        self.helper, self.call, self.done, self.outcome = helper, (fn, args, kwargs), False, None

    def result(self) -> Any:
        """The call's return value (its exception raised here); waits for the helper."""
        while not self.done and self.helper is not None and self.helper.alive:
            self.helper.receive_one()
        if not self.done:  # no helper, or it went away: the same call here
            fn, args, kwargs = self.call
            self.done, self.outcome = True, ("ok", fn(*args, **kwargs))
        kind, value = self.outcome
        if kind == "error":
            raise value
        return value


class _Helper:
    """One helper's pipe; its jobs are answered in the order they were sent."""

    def __init__(self, connection: Any) -> None:
        self.connection = connection
        self.waiting: deque[_Job] = deque()
        self.alive = True

    def send(self, job: _Job) -> None:
        try:
            self.connection.send(job.call)
        except Exception:  # noqa: BLE001 - unpicklable or a broken pipe: the job runs here instead
            job.helper = None
            return
        self.waiting.append(job)

    def receive_one(self) -> None:
        """The oldest waiting job's outcome; a helper that went away leaves its jobs to run here."""
        try:
            outcome = self.connection.recv()
        except (EOFError, OSError):
            self.alive = False
            for job in self.waiting:
                job.helper = None
            self.waiting.clear()
            return
        job = self.waiting.popleft()
        job.done, job.outcome = True, outcome


def _start(count: int, warm: Sequence[str]) -> tuple[list[_Helper], Any]:
    """``count`` helpers: the first is forked from here, imports ``warm`` and then forks the others from
    itself, so the imports are done once and their pages shared. Returns the helpers and the first's process."""
    context = multiprocessing.get_context("fork")
    pipes = [context.Pipe() for _ in range(count)]
    ours, theirs = [mine for mine, _ in pipes], [other for _, other in pipes]
    process = context.Process(target=_first, args=(ours, theirs, tuple(warm)), daemon=True)
    process.start()
    for end in theirs:
        end.close()
    return [_Helper(end) for end in ours], process


def _first(ours: list[Any], theirs: list[Any], warm: tuple[str, ...]) -> None:
    """The first helper: import ``warm``, fork one helper per further pipe, serve the first pipe, and wait
    for the others to leave before leaving (each leaves when the caller closes its pipe)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the caller's to handle; it then closes the pipes
    for end in ours:  # held open here, a pipe would never reach its end
        end.close()
    for name in warm:
        with contextlib.suppress(Exception):  # a job needing it raises the same error, and is reported
            importlib.import_module(name)
    children = []
    for i in range(1, len(theirs)):
        pid = os.fork()
        if pid == 0:
            try:
                for j, end in enumerate(theirs):
                    if j != i:
                        end.close()
                _serve(theirs[i])
            finally:
                os._exit(0)
        children.append(pid)
    for end in theirs[1:]:
        end.close()
    _serve(theirs[0])
    for pid in children:
        os.waitpid(pid, 0)
    os._exit(0)


def _serve(connection: Any) -> None:
    """Answer each call sent until the pipe closes (or the caller has gone)."""
    while True:
        try:
            fn, args, kwargs = connection.recv()
        except (EOFError, OSError):
            return
        try:
            outcome = ("ok", fn(*args, **kwargs))
        except Exception as error:  # noqa: BLE001 - sent back and raised in the caller
            outcome = ("error", error)
        if not _send(connection, outcome):
            return


def _send(connection: Any, outcome: tuple[str, Any]) -> bool:
    """Send a job's outcome (an unpicklable one as an error); False when the caller has gone."""
    try:
        connection.send(outcome)
        return True
    except (BrokenPipeError, ConnectionError, EOFError, OSError):
        return False
    except Exception as error:  # noqa: BLE001 - an unpicklable result or exception
        return _send(connection, ("error", RuntimeError(f"a helper's result could not be sent back: {error!r}")))


class Helpers:
    """Submit calls to the helper with the fewest waiting jobs (or run them here when there is none)."""

    def __init__(self, helpers: list[_Helper], process: Any = None) -> None:
        self._helpers, self.process = helpers, process  # the first helper's process (None: no helpers)

    @property
    def count(self) -> int:
        """How many helper processes run (0: every job runs in the calling process)."""
        return len(self._helpers)

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> _Job:
        """``fn(*args, **kwargs)`` in a helper; ``.result()`` gives what it returned. ``fn`` is a
        module-level function (it is sent by name) and its arguments picklable."""
        live = [helper for helper in self._helpers if helper.alive]
        helper = min(live, key=lambda h: len(h.waiting)) if live else None
        job = _Job(helper, fn, args, kwargs)
        if helper is not None:
            helper.send(job)
        return job


def can_fork() -> bool:
    """Whether forking is safe here: ``fork`` exists and this process runs one Python thread."""
    return "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1


@contextlib.contextmanager
def forked_helpers(count: int, warm: Sequence[str] = ()) -> Iterator[Helpers]:
    """``count`` helper processes that import the modules named in ``warm`` at once; ended when the block
    ends (each reads the end of its pipe; all are waited for, or killed when the block raised with jobs
    still out). None are forked where :func:`can_fork` is false: the jobs then run in this process."""
    helpers, process = ([], None) if count < 1 or not can_fork() else _start(count, warm)
    try:
        yield Helpers(helpers, process)
    finally:
        for helper in helpers:
            helper.connection.close()
        if process is not None:
            if not any(helper.waiting for helper in helpers):
                process.join(timeout=5)
            if process.is_alive():
                process.kill()
                process.join()
