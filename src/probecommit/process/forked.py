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
    """One forked process and its pipe; jobs are answered in the order they were sent."""

    def __init__(self, warm: Sequence[str], others: Sequence[Any] = ()) -> None:
        context = multiprocessing.get_context("fork")
        self.connection, theirs = context.Pipe()
        # Its copy of our end and of the earlier helpers' pipes are closed in the helper: held open, a helper
        # would never see its pipe's end.
        self.process = context.Process(target=_serve, args=(theirs, tuple(warm), (*others, self.connection)),
                                       daemon=True)
        self.process.start()
        theirs.close()
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

    def close(self) -> None:
        """End the helper: it reads the end of its pipe and exits; one still working (the caller raised) is killed."""
        self.connection.close()
        if not self.waiting:
            self.process.join(timeout=5)
        if self.process.is_alive():
            self.process.kill()
            self.process.join()


def _serve(connection: Any, warm: tuple[str, ...], others: tuple[Any, ...]) -> None:
    """A helper's life: import ``warm``, then answer each call sent until the pipe closes."""
    for other in others:
        other.close()
    for name in warm:
        with contextlib.suppress(Exception):  # a job needing it raises the same error, and is reported
            importlib.import_module(name)
    while True:
        try:
            fn, args, kwargs = connection.recv()
        except (EOFError, OSError):
            break
        try:
            outcome = ("ok", fn(*args, **kwargs))
        except Exception as error:  # noqa: BLE001 - sent back and raised in the caller
            outcome = ("error", error)
        if not _send(connection, outcome):
            break
    os._exit(0)


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

    def __init__(self, helpers: list[_Helper]) -> None:
        self._helpers = helpers

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
    """``count`` helper processes that import the modules named in ``warm`` at once; closed (each
    told to exit, then joined) when the block ends. None are forked where :func:`can_fork` is
    false: the jobs then run in this process."""
    helpers: list[_Helper] = []
    try:
        if can_fork():
            for _ in range(count):
                helpers.append(_Helper(warm, [helper.connection for helper in helpers]))
        yield Helpers(helpers)
    finally:
        for helper in helpers:
            helper.close()
