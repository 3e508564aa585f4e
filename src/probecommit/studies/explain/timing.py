"""How long each explain step took: a progress callback that logs wall and CPU seconds per step.

The explain target runs for many minutes (issue 42); a user asked for progress on long work, and a
profile needs per-step costs. Every step already reports its label through ``progress``; this
wrapper closes the previous label's clock whenever a new label arrives and logs it at INFO on the
``probecommit`` logger (``probecommit -v reproduce explain`` shows it), so no step needs its own
timing code and a step added later is timed too.
"""

from __future__ import annotations

import logging
import time
from typing import Callable

logger = logging.getLogger(__name__)

Progress = Callable[[str, int, int], None]


class StepClock:
    """``progress`` passed through, with each label's wall and CPU seconds logged when the next begins.

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
        logger.info("%s: %.1f s wall, %.1f s CPU", self._label, wall, cpu)
        self._label = None
