"""Guarded engine imports: a missing engine names the extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

from probecommit.errors import UserError

ENGINE_EXTRAS = {"mujoco": "mujoco", "pybullet": "pybullet", "sapien": "sapien", "ray": "ray"}


class EngineUnavailableError(UserError, ImportError):
    """Raised when an optional physics engine (or Ray) is not installed."""


def require(module: str) -> ModuleType:
    """Import an optional engine module or raise an error naming the extra.

    Args:
        module: ``"mujoco"``, ``"pybullet"``, ``"sapien"`` or ``"ray"``.
    """
    try:
        if module == "mujoco":
            return _import_mujoco_headless()
        return importlib.import_module(module)
    except ImportError as exc:  # pragma: no cover - exercised only without the engine
        extra = ENGINE_EXTRAS.get(module.split(".")[0], module)
        raise EngineUnavailableError(
            f"{module} is not installed; install it with: pip install 'probecommit[{extra}]'"
        ) from exc


def _import_mujoco_headless() -> ModuleType:
    """``import mujoco`` for physics: with ``MUJOCO_GL`` unset, MuJoCo loads GLFW's bindings at import,
    whose cffi parses C declarations (about 0.5 s of CPU in every process that runs a MuJoCo query).
    Physics needs no GL context, so the first import runs with ``MUJOCO_GL=disable`` (restored
    after: a child process chooses its own back-end; scene renders run in one with ``MUJOCO_GL`` set,
    ``report.scenes``). A back-end the user set is kept."""
    import os
    import sys

    if "mujoco" in sys.modules or "MUJOCO_GL" in os.environ:
        return importlib.import_module("mujoco")
    os.environ["MUJOCO_GL"] = "disable"
    try:
        return importlib.import_module("mujoco")
    finally:
        os.environ.pop("MUJOCO_GL", None)


def silenced_fds():
    """Context manager: fds 1 and 2 (C-level prints too) and Python warnings go to /dev/null.

    Engine imports print banners (PyBullet's build time, SAPIEN's libvulkan warning) from
    C code, which ``contextlib.redirect_stdout`` cannot catch.
    """
    import contextlib, os, sys, warnings  # noqa: E401  (kept local: one self-contained hunk)

    @contextlib.contextmanager
    def _silenced():
        sys.stdout.flush(), sys.stderr.flush()
        saved, null = [os.dup(1), os.dup(2)], os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, 1), os.dup2(null, 2)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                yield
        finally:
            sys.stdout.flush(), sys.stderr.flush()
            os.dup2(saved[0], 1), os.dup2(saved[1], 2)
            for fd in (*saved, null):
                os.close(fd)

    return _silenced()
