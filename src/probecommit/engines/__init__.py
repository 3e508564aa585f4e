"""Guarded engine imports: a missing engine names the extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

ENGINE_EXTRAS = {"mujoco": "mujoco", "pybullet": "pybullet", "sapien": "sapien", "ray": "ray"}


class EngineUnavailableError(ImportError):
    """Raised when an optional physics engine (or Ray) is not installed."""


def require(module: str) -> ModuleType:
    """Import an optional engine module or raise an error naming the extra.

    Args:
        module: ``"mujoco"``, ``"pybullet"``, ``"sapien"`` or ``"ray"``.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:  # pragma: no cover - exercised only without the engine
        extra = ENGINE_EXTRAS.get(module.split(".")[0], module)
        raise EngineUnavailableError(
            f"{module} is not installed; install it with: pip install 'probecommit[{extra}]'"
        ) from exc
