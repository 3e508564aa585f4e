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
from pathlib import Path as _Path


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


def _version() -> str:
    """The installed distribution's version (pyproject.toml, one source), read on first use:
    ``importlib.metadata`` costs about 50 ms, which ``--help`` need not pay."""
    from importlib import metadata as _metadata

    try:
        return _metadata.version("probecommit")
    except _metadata.PackageNotFoundError:  # running from a source tree without install
        return "0.0.0+unknown"


def __getattr__(name: str):
    if name == "__version__":
        globals()["__version__"] = version = _version()  # once: later reads find the attribute
        return version
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        return getattr(importlib.import_module(module), attribute)
    raise AttributeError(f"module 'probecommit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
