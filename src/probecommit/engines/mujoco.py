"""MuJoCo plumbing shared by every task family: one data buffer per memory layout.

A compiled ``MjModel`` is a pure function of its scene and a query writes only ``MjData``,
so families keep compiled instances in a process-wide :class:`~probecommit.engines.cache.InstanceCache`
and each simulator keeps one ``MjData`` per layout (:class:`DataBuffers`), shared by every
instance whose model has that layout. A query must then set (or reset) every piece of
state it reads; each family's tests check that interleaving instances changes no answer.
Buffers are per thread, so a simulator's queries can run in engine threads at once
(:meth:`probecommit.tasks.base.CachedSimulator.prefetch`).
"""

from __future__ import annotations

import threading
from typing import Any


def data_layout(model: Any) -> tuple[int, ...]:
    """The model's integer size fields (``nq``, ``nbody``, ``ncon`` buffers, ...) in name order:
    two models with the same layout can use the same ``MjData``."""
    return tuple(getattr(model, name) for name in sorted(dir(model))
                 if name.startswith("n") and isinstance(getattr(model, name, None), int))


class DataBuffers:
    """One ``MjData`` per memory layout and thread, made on first use.

    Args:
        mj: The imported ``mujoco`` module (the caller imports it lazily).
    """

    def __init__(self, mj: Any) -> None:
        self._mj = mj
        self._local = threading.local()

    @property
    def _data(self) -> dict[tuple[int, ...], Any]:
        """The calling thread's buffers by layout."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = self._local.data = {}
        return data

    def get(self, model: Any, layout: tuple[int, ...]) -> Any:
        """The calling thread's buffer for ``model``, whose :func:`data_layout` is ``layout``
        (computed once, by the caller's cache)."""
        buffers = self._data
        data = buffers.get(layout)
        if data is None:
            data = buffers[layout] = self._mj.MjData(model)
        return data

    def __len__(self) -> int:
        """Buffers of the calling thread."""
        return len(self._data)
