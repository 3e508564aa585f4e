"""How long each explain step took: a progress callback that logs wall and CPU seconds per step.

The explain target runs for many minutes (issue 42); a user asked for progress on long work, and a
profile needs per-step costs. Every step already reports its label through ``progress``; this
wrapper closes the previous label's clock whenever a new label arrives and logs it at INFO on the
``probecommit`` logger (``probecommit -v reproduce explain`` shows it), so no step needs its own
timing code and a step added later is timed too.
"""

from __future__ import annotations

import logging
import sys
import time
from typing import Callable

logger = logging.getLogger(__name__)

Progress = Callable[[str, int, int], None]


def peak_mb() -> float:
    """This process's peak resident set size so far, in MB (0 where the platform does not say)."""
    try:  # this process's own high-water mark (a spawned process's ru_maxrss starts at its parent's at the fork)
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmHWM")) / 1024
    except (OSError, StopIteration, ValueError):
        pass
    try:
        import resource
    except ImportError:  # not on Windows
        return 0.0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 1024  # bytes on macOS, KiB on Linux


def children_cpu() -> float:
    """CPU seconds of this process's ended child processes so far (0 where the platform does not say)."""
    try:
        import resource
    except ImportError:  # not on Windows
        return 0.0
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


class StepClock:
    """``progress`` passed through, with each label's wall and CPU seconds logged when the next begins, and
    the process's peak resident memory so far (what a step that holds too much shows as a jump).

    ``steps`` keeps ``(label, wall_s, cpu_s, child_cpu_s)`` in order (a label reported again later is a new
    entry); ``child_cpu_s`` is the CPU of the worker processes the step's runs started and ended (a study's
    ``--workers``), counted once they are reaped.
    """

    def __init__(self, progress: Progress) -> None:
        self.inner = progress
        self.steps: list[tuple[str, float, float, float]] = []
        self._label: str | None = None
        self._wall = self._cpu = self._children = 0.0

    def __call__(self, label: str, done: int, total: int) -> None:
        if label != self._label and not label == "explain":  # "explain" i/n only counts the steps
            self.close()
            self._label, self._wall, self._cpu = label, time.perf_counter(), time.process_time()
            self._children = children_cpu()
        self.inner(label, done, total)

    def close(self) -> None:
        """End the current label's clock (the last step's, at the end of the run)."""
        if self._label is None:
            return
        wall, cpu = time.perf_counter() - self._wall, time.process_time() - self._cpu
        children = children_cpu() - self._children
        self.steps.append((self._label, wall, cpu, children))
        logger.info("%s: %.1f s wall, %.1f s CPU (+%.1f s in worker processes), peak %.0f MB", self._label, wall, cpu,
                    children, peak_mb())
        self._label = None
