"""probecommit: probe a few times, commit once, audit offline."""

from __future__ import annotations

from importlib import metadata as _metadata
from importlib import resources as _resources
from pathlib import Path as _Path

try:  # one source for the version: the installed distribution's metadata (pyproject.toml)
    __version__ = _metadata.version("probecommit")
except _metadata.PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"


def paper_config(name: str) -> _Path:
    """Path of a frozen paper config shipped with the package (``configs/paper/<name>.yaml``).

    Raises:
        FileNotFoundError: naming the configs that exist.
    """
    folder = _Path(str(_resources.files("probecommit") / "configs" / "paper"))
    path = folder / (name if name.endswith(".yaml") else f"{name}.yaml")
    if not path.is_file():
        have = ", ".join(sorted(p.stem for p in folder.glob("*.yaml")))
        raise FileNotFoundError(f"no paper config {name!r}; shipped: {have}")
    return path


def __getattr__(name: str):
    # Lazy: ``import probecommit`` stays light; ``probecommit.Session`` imports the robot API on first use.
    if name == "Session":
        import importlib

        # By name, so the package root stays below every layer (import-linter).
        return importlib.import_module("probecommit.robot.session").Session
    if name in ("check_family", "FamilyCheckError"):
        import importlib

        return getattr(importlib.import_module("probecommit.runner.family_check"), name)
    raise AttributeError(f"module 'probecommit' has no attribute {name!r}")
