"""A per-instance LRU of engine objects: a compiled model and its data, a scene, a plate body.

Every engine simulator keeps the expensive part of a ground-truth instance (compiling an
MJCF, building a PhysX scene, creating a Bullet body) across queries on that instance,
and bounds how many it keeps. The queries themselves are cached above this, in
:class:`probecommit.tasks.base.CachedSimulator`, so an eviction costs one rebuild.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from inspect import ismethod
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
        # A simulator keeps its cache and the cache its builders: held strongly, a bound method
        # of the simulator would close a reference cycle, and every simulator (with its compiled
        # engine instances, C memory the garbage collector does not see) would live until the
        # next full collection. Held weakly, a simulator's instances go when it does.
        self._build = _weak(build)
        self._evict = None if evict is None else _weak(evict)
        self._size = int(size)
        self._entries: OrderedDict[tuple[float, ...], Any] = OrderedDict()
        # Engine threads (CachedSimulator.prefetch) share the cache: one builder at a time.
        self._lock = threading.Lock()

    def get(self, *key: float) -> Any:
        """The entry of instance ``key``, built on first use (thread-safe)."""
        key = tuple(float(k) for k in key)
        with self._lock:
            return self._get(key)

    def _get(self, key: tuple[float, ...]) -> Any:
        entry = self._entries.get(key)
        if entry is not None:
            self._entries.move_to_end(key)
            return entry
        build = self._build()
        if build is None:
            raise ReferenceError("the object whose method builds this cache's entries no longer exists")
        entry = self._entries[key] = build(*key)
        if len(self._entries) > self._size:
            old_key, old = self._entries.popitem(last=False)
            evict = None if self._evict is None else self._evict()
            if evict is not None:
                evict(old_key, old)
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


def _weak(function: Callable[..., Any]) -> Callable[[], Callable[..., Any]]:
    """A getter of ``function`` that holds a bound method's object weakly (anything else strongly)."""
    if ismethod(function):
        return weakref.WeakMethod(function)  # type: ignore[return-value]
    return lambda: function
