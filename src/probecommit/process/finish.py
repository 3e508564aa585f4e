"""A command's end without the interpreter's teardown.

When a command has finished, CPython still frees every module and object before the process
ends: for ``probecommit run`` (pandas, pyarrow, numpy and a run's arrays loaded) that took
about 0.12-0.14 s of CPU, a fifth of a 4-episode run's and 6 % of the 480 x 4 study's, and bought
nothing (the operating system takes the memory back at once). :func:`exit_process` does the
part of interpreter exit that has effects (joins the non-daemon threads and runs the threading
module's exit hooks, as finalization does first, then every ``atexit`` handler: log handlers
flushed, temporary directories removed, thread pools joined; then the console streams flushed)
and ends the process with the command's status, skipping only the teardown.
"""

from __future__ import annotations

import atexit
import os
import sys
import threading


def exit_status(code: object) -> int:
    """The process status ``sys.exit(code)`` gives: None is 0, an integer itself, anything else
    is printed to stderr and gives 1."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def exit_process(code: object = 0) -> None:
    """End the process as ``sys.exit(code)`` at the end of the program would, without tearing
    the interpreter down. Where the threading module has no exit hook to call (another Python),
    it is ``sys.exit(code)``."""
    shutdown = getattr(threading, "_shutdown", None)
    if shutdown is None or threading.current_thread() is not threading.main_thread():
        sys.exit(code)
    status = exit_status(code)
    shutdown()  # non-daemon threads joined, concurrent.futures' pools shut down: what finalization does first
    atexit._run_exitfuncs()  # noqa: SLF001 - the handlers interpreter exit would run next
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (``| head``) or stream: nothing more to write
            pass
    os._exit(status)
