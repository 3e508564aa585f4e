"""probecommit: probe a few times, commit once, audit offline.

The public Python API (``dir(probecommit)``)::

    import probecommit
    result = probecommit.audit_run("runs/demo")   # or audit_log("my_robot_log.csv")
    result.to_frame()                             # tidy pandas: one row per method, budget, metric
    result.plot()                                 # the report's figure (a matplotlib Figure)
    result                                        # in a notebook: the table and the figure

    session = probecommit.Session(...)            # the online robot loop (docs/robot.md)
    probecommit.paper_config("insertion")         # a frozen paper config

Every module logs under the ``probecommit`` logger. The package adds only a
``NullHandler``: a program that imports it decides where the messages go
(``logging.getLogger("probecommit").setLevel(logging.WARNING)`` silences the rest).
The attributes load on first use, so ``import probecommit`` stays light.
"""

from __future__ import annotations

import logging as _logging
import os as _os
import sys as _sys
from pathlib import Path as _Path


def _distribution_version(name: str) -> str | None:
    """The ``Version:`` of the first distribution ``name`` on ``sys.path``, as
    ``importlib.metadata.version`` finds it, read from its ``*.dist-info/METADATA`` headers
    directly: importing ``importlib.metadata`` (and its e-mail parser) costs every command,
    ``--help`` included, about 50 ms. None when it is not installed."""
    wanted = name.lower().replace("-", "_")
    for folder in _sys.path:
        try:
            entries = sorted(e.name for e in _os.scandir(folder or "."))
        except OSError:
            continue
        for entry in entries:
            stem, dot, suffix = entry.rpartition(".")
            if suffix != "dist-info" or stem.rpartition("-")[0].lower().replace("-", "_").replace(".", "_") != wanted:
                continue
            try:
                with open(_os.path.join(folder or ".", entry, "METADATA"), encoding="utf-8") as fh:
                    for line in fh:
                        if not line.strip():
                            break
                        if line.startswith("Version:"):
                            return line[len("Version:"):].strip()
            except OSError:
                continue
    return None


# One source for the version: the installed distribution's metadata (pyproject.toml).
__version__ = _distribution_version("probecommit")
if __version__ is None:  # pragma: no cover - an egg or an unusual installer: ask importlib
    from importlib import metadata as _metadata

    try:
        __version__ = _metadata.version("probecommit")
    except _metadata.PackageNotFoundError:  # running from a source tree without install
        __version__ = "0.0.0+unknown"

_logging.getLogger(__name__).addHandler(_logging.NullHandler())

#: Lazy public attributes: name -> (module, attribute). Imported by name, so the package root
#: stays below every layer (import-linter) and ``import probecommit`` imports none of them.
_LAZY = {
    "Session": ("probecommit.robot.session", "Session"),
    "audit_run": ("probecommit.report.notebook", "audit_run"),
    "audit_log": ("probecommit.report.notebook", "audit_log"),
    "AuditReport": ("probecommit.report.notebook", "AuditReport"),
    "UserError": ("probecommit.errors", "UserError"),
    "check_family": ("probecommit.runner.family_check", "check_family"),
    "FamilyCheckError": ("probecommit.runner.family_check", "FamilyCheckError"),
}

__all__ = ["__version__", "paper_config", *_LAZY]


def paper_config(name: str) -> _Path:
    """Path of a frozen paper config shipped with the package (``configs/paper/<name>.yaml``).

    Raises:
        FileNotFoundError: naming the configs that exist.
    """
    from importlib import resources as _resources

    folder = _Path(str(_resources.files("probecommit") / "configs" / "paper"))
    path = folder / (name if name.endswith(".yaml") else f"{name}.yaml")
    if not path.is_file():
        have = ", ".join(sorted(p.stem for p in folder.glob("*.yaml")))
        raise FileNotFoundError(f"no paper config {name!r}; shipped: {have}")
    return path


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        return getattr(importlib.import_module(module), attribute)
    raise AttributeError(f"module 'probecommit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
