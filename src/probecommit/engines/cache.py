"""A per-instance LRU of engine objects: a compiled model and its data, a scene, a plate body.

Every engine simulator keeps the expensive part of a ground-truth instance (compiling an
MJCF, building a PhysX scene, creating a Bullet body) across queries on that instance,
and bounds how many it keeps. The queries themselves are cached above this, in
:class:`probecommit.tasks.base.CachedSimulator`, so an eviction costs one rebuild.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any, Callable


class InstanceCache:
    """Least-recently-used cache of ``build(*key)`` per instance key (a tuple of floats).

    Args:
        build: Builds the entry of an instance from its key's values.
        size: Entries kept; the least recently used is dropped beyond it.
        evict: Called as ``evict(key, entry)`` on a dropped entry (to free engine-side
            resources); None when dropping the Python reference is enough.
    """

    def __init__(self, build: Callable[..., Any], size: int, evict: Callable[[tuple, Any], None] | None = None) -> None:
        if size < 1:
            raise ValueError(f"cache size must be >= 1, got {size!r}")
        self._build = build
        self._size = int(size)
        self._evict = evict
        self._entries: OrderedDict[tuple[float, ...], Any] = OrderedDict()

    def get(self, *key: float) -> Any:
        """The entry of instance ``key``, built on first use."""
        key = tuple(float(k) for k in key)
        entry = self._entries.get(key)
        if entry is not None:
            self._entries.move_to_end(key)
            return entry
        entry = self._entries[key] = self._build(*key)
        if len(self._entries) > self._size:
            old_key, old = self._entries.popitem(last=False)
            if self._evict is not None:
                self._evict(old_key, old)
        return entry

    def values(self) -> list[Any]:
        """The entries, least recently used first."""
        return list(self._entries.values())

    def clear(self) -> None:
        """Drop every entry (``evict`` is not called: the caller is tearing the engine down)."""
        self._entries.clear()

    def __contains__(self, key: tuple[float, ...]) -> bool:
        return tuple(float(k) for k in key) in self._entries

    def __len__(self) -> int:
        return len(self._entries)
