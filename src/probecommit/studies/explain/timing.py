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
    try:
        import resource
    except ImportError:  # not on Windows
        return 0.0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 1024  # bytes on macOS, KiB on Linux


class StepClock:
    """``progress`` passed through, with each label's wall and CPU seconds logged when the next begins, and
    the process's peak resident memory so far (what a step that holds too much shows as a jump).

    ``steps`` keeps ``(label, wall_s, cpu_s)`` in order (a label reported again later is a new entry).
    """

    def __init__(self, progress: Progress) -> None:
        self.inner = progress
        self.steps: list[tuple[str, float, float]] = []
        self._label: str | None = None
        self._wall = self._cpu = 0.0

    def __call__(self, label: str, done: int, total: int) -> None:
        if label != self._label and not label == "explain":  # "explain" i/n only counts the steps
            self.close()
            self._label, self._wall, self._cpu = label, time.perf_counter(), time.process_time()
        self.inner(label, done, total)

    def close(self) -> None:
        """End the current label's clock (the last step's, at the end of the run)."""
        if self._label is None:
            return
        wall, cpu = time.perf_counter() - self._wall, time.process_time() - self._cpu
        self.steps.append((self._label, wall, cpu))
        logger.info("%s: %.1f s wall, %.1f s CPU, peak %.0f MB", self._label, wall, cpu, peak_mb())
        self._label = None
