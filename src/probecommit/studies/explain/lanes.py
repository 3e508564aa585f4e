"""The rule steps set aside rely on, checked: no later main-lane step reads what a step set aside fills.

A step set aside (``Explain.aside``) runs in a process of its own beside the later steps; its keys, stored
rows and tables are merged when it is handed on, which may be before or after any later step (inline at
once on one CPU, at the end on two). A later step reading them would see them or not by machine and load,
where run in place it always would, so its numbers would depend on the schedule. ``Reads`` records the last
step at which the main lane read each entry; ``check``, once every job is merged, compares those reads
with what each job aside filled and names the first step that breaks the rule. A step that needs what a
job aside fills waits for it first (``Explain.wait_aside``): from then on every run sees it merged. Every
job in a process of its own counts, whether set aside (``Explain.aside``) or submitted (``Explain.submit``):
what its hand-on writes is recorded as that job's.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Iterator

#: The key noted when a step reads a whole group (iterates it, copies it, lists its values).
WHOLE = "*"

Entry = tuple[str, str, str]  # (where: res / stored / tables, group ("" for rows and tables), key or file name)


class Reads:
    """Which entries the main lane read, by step, and what each job set aside filled."""

    def __init__(self) -> None:
        self.step = -1  # the step running now (``Explain.run_steps`` sets it)
        self._clock = 0  # counts reads, submissions and waits, in the order the main lane made them
        self.log: dict[Entry, list[tuple[int, int]]] = {}  # entry -> (clock, step) of each read
        self.jobs: list[dict[str, Any]] = []
        self._paused = 0
        self._recording: int | None = None  # the job whose hand-on is writing now

    def _tick(self) -> int:
        self._clock += 1
        return self._clock

    def note(self, where: str, group: str, key: Any) -> None:
        if not self._paused and self._recording is None:  # a job's hand-on reads as the job, not as a step
            self.log.setdefault((where, group, str(key)), []).append((self._tick(), self.step))

    def submitted(self, label: str) -> int:
        """A job set aside now; its number, for :meth:`filled`."""
        self.jobs.append({"label": label, "step": self.step, "start": self._tick(), "end": None, "entries": set()})
        return len(self.jobs) - 1

    def waited(self) -> None:
        """The main lane waited for every job set aside so far: later reads see them merged on every run."""
        clock = self._tick()
        for job in self.jobs:
            job["end"] = clock if job["end"] is None else job["end"]

    def wrote(self, where: str, group: str, key: Any) -> None:
        if self._recording is not None and not self._paused:
            self.jobs[self._recording]["entries"].add((where, group, str(key)))

    @contextmanager
    def recording(self, job: int) -> Iterator[None]:
        """What is written inside is what job ``job`` filled (its hand-on runs here)."""
        self._recording = job
        try:
            yield
        finally:
            self._recording = None

    @contextmanager
    def paused(self) -> Iterator[None]:
        """The bookkeeping's own reads and rewrites (where to put merged keys) are not a step's."""
        self._paused += 1
        try:
            yield
        finally:
            self._paused -= 1

    def filled(self, job: int, entries: set[Entry]) -> None:
        """Job ``job`` was merged and filled ``entries`` (beside what its hand-on wrote)."""
        self.jobs[job]["entries"] |= entries

    def check(self) -> None:
        """Raises:
            RuntimeError: a main-lane step read an entry that a job filled after setting it aside and before
                waiting for it."""
        for job in self.jobs:
            groups = {(where, group) for where, group, _ in job["entries"]}
            end = float("inf") if job["end"] is None else job["end"]
            for (where, group, key), reads in self.log.items():
                if (where, group, key) not in job["entries"] and not (key == WHOLE and (where, group) in groups):
                    continue
                for clock, step in reads:
                    if job["start"] < clock < end:
                        raise RuntimeError(
                            f"explain: step {step} reads {where} {group + ' ' if group else ''}{key!r}, which "
                            f"{job['label']} (set aside at step {job['step']}) fills; wait for it first "
                            f"(Explain.wait_aside), set that step aside in the same job, or run it in place")


class ReadDict(dict):
    """A dict whose reads are noted in ``reads`` as ``(where, group, key)``; writes are not reads."""

    def __init__(self, reads: Reads, where: str, group: str = "", *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._reads, self._where, self._group = reads, where, group

    def _note(self, key: Any) -> None:
        self._reads.note(self._where, self._group, key)

    def __setitem__(self, key: Any, value: Any) -> None:
        self._reads.wrote(self._where, self._group, key)
        super().__setitem__(key, value)

    def update(self, *args: Any, **kwargs: Any) -> None:
        for key in dict(*args, **kwargs):
            self._reads.wrote(self._where, self._group, key)
        super().update(*args, **kwargs)

    def __getitem__(self, key: Any) -> Any:
        self._note(key)
        return super().__getitem__(key)

    def get(self, key: Any, default: Any = None) -> Any:
        self._note(key)
        return super().get(key, default)

    def pop(self, key: Any, *default: Any) -> Any:
        self._note(key)
        return super().pop(key, *default)

    def __contains__(self, key: Any) -> bool:
        self._note(key)
        return super().__contains__(key)

    def __iter__(self) -> Iterator[Any]:
        self._note(WHOLE)
        return super().__iter__()

    def keys(self) -> Any:
        self._note(WHOLE)
        return super().keys()

    def values(self) -> Any:
        self._note(WHOLE)
        return super().values()

    def items(self) -> Any:
        self._note(WHOLE)
        return super().items()

    def copy(self) -> dict[Any, Any]:
        self._note(WHOLE)
        return dict(super().items())

    def __reduce__(self) -> Any:  # crosses processes as a plain dict (what a job aside hands back)
        return (dict, (dict(super().items()),))
