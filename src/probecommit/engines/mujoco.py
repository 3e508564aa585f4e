"""MuJoCo plumbing shared by every task family: one data buffer per memory layout.

A compiled ``MjModel`` is a pure function of its scene and a query writes only ``MjData``,
so families keep compiled instances in a process-wide :class:`~probecommit.engines.cache.InstanceCache`
and each simulator keeps one ``MjData`` per layout (:class:`DataBuffers`), shared by every
instance whose model has that layout. A query must then set (or reset) every piece of
state it reads; each family's tests check that interleaving instances changes no answer.
"""

from __future__ import annotations

from typing import Any


def data_layout(model: Any) -> tuple[int, ...]:
    """The model's integer size fields (``nq``, ``nbody``, ``ncon`` buffers, ...) in name order:
    two models with the same layout can use the same ``MjData``."""
    return tuple(getattr(model, name) for name in sorted(dir(model))
                 if name.startswith("n") and isinstance(getattr(model, name, None), int))


class DataBuffers:
    """One ``MjData`` per memory layout, made on first use.

    Args:
        mj: The imported ``mujoco`` module (the caller imports it lazily).
    """

    def __init__(self, mj: Any) -> None:
        self._mj = mj
        self._data: dict[tuple[int, ...], Any] = {}

    def get(self, model: Any, layout: tuple[int, ...]) -> Any:
        """The buffer for ``model``, whose :func:`data_layout` is ``layout`` (computed once, by the caller's cache)."""
        data = self._data.get(layout)
        if data is None:
            data = self._data[layout] = self._mj.MjData(model)
        return data

    def __len__(self) -> int:
        return len(self._data)
