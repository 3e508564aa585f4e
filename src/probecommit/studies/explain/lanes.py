"""The rule steps set aside rely on, checked: no later main-lane step reads what a step set aside fills.

A step set aside (``Explain.aside``) runs in a process of its own beside the later steps; its keys, stored
rows and tables are merged when it is handed on, which may be before or after any later step (inline at
once on one CPU, at the end on two). A later step reading them would see them or not by machine and load,
where run in place it always would, so its numbers would depend on the schedule. ``Reads`` records the last
step at which the main lane read each entry; ``check``, once every job is merged, compares those reads
with what each job aside filled and names the first step that breaks the rule.
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
        self.last: dict[Entry, int] = {}
        self.asides: list[tuple[int, str, set[Entry]]] = []
        self._paused = 0

    def note(self, where: str, group: str, key: Any) -> None:
        if not self._paused:
            self.last[(where, group, str(key))] = self.step

    @contextmanager
    def paused(self) -> Iterator[None]:
        """The bookkeeping's own reads (where to put merged keys) are not a step's."""
        self._paused += 1
        try:
            yield
        finally:
            self._paused -= 1

    def filled(self, at: int, label: str, entries: set[Entry]) -> None:
        """A job set aside at step ``at`` was merged and filled ``entries``."""
        self.asides.append((at, label, entries))

    def check(self) -> None:
        """Raises:
            RuntimeError: a main-lane step after a job's submission read an entry that job filled."""
        for at, label, entries in self.asides:
            groups = {(where, group) for where, group, _ in entries}
            for (where, group, key), step in self.last.items():
                hit = (where, group, key) in entries or (key == WHOLE and (where, group) in groups)
                if step > at and hit:
                    raise RuntimeError(
                        f"explain: step {step} reads {where} {group + ' ' if group else ''}{key!r}, which {label} "
                        f"(set aside at step {at}) fills; set that step aside in the same job or run {label} in place")


class ReadDict(dict):
    """A dict whose reads are noted in ``reads`` as ``(where, group, key)``; writes are not reads."""

    def __init__(self, reads: Reads, where: str, group: str = "", *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._reads, self._where, self._group = reads, where, group

    def _note(self, key: Any) -> None:
        self._reads.note(self._where, self._group, key)

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
