"""The task registry: families register a :class:`~probecommit.tasks.base.TaskSpec` by name.

Built-in families live in ``probecommit.tasks.<family>`` and register on import: every
subpackage of :mod:`probecommit.tasks` is imported on first use of the registry (a new
family is a new folder, no list to edit). Third-party families register through the
``probecommit.tasks`` entry-point group,
whose entry points name a module (imported, so it registers itself) or a callable
returning a ``TaskSpec``. Simulators are lazy ``"module:Class"`` entry points: an
engine is imported only when a study asks for it.
"""

from __future__ import annotations

import importlib
import pkgutil
from importlib.metadata import entry_points
from typing import Any

from probecommit.tasks.base import TaskSpec, answer_store
from probecommit.errors import UserError

ENTRY_POINT_GROUP = "probecommit.tasks"

_REGISTRY: dict[str, TaskSpec] = {}
_loaded = False


class UnknownTaskError(UserError, KeyError):
    """An unknown family, or an engine a family lacks; the message lists what exists."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


def registered(name: str, *, declared: bool = False) -> bool:
    """Whether ``name`` is registered now (without loading the built-ins); ``declared``: and was
    derived from a :class:`~probecommit.tasks.declare.Declaration`."""
    spec = _REGISTRY.get(name)
    return spec is not None and (not declared or spec.declaration is not None)


def register(spec: TaskSpec, *, replace: bool = False) -> TaskSpec:
    """Register a family (idempotent for the same spec object; a different one is refused unless ``replace``)."""
    existing = _REGISTRY.get(spec.name)
    if existing is not None and not replace and existing is not spec and existing != spec:
        raise ValueError(f"task family {spec.name!r} is already registered")
    _REGISTRY[spec.name] = spec
    return spec


def builtin_packages() -> list[str]:
    """The subpackages of :mod:`probecommit.tasks` (each family's folder, plus helpers such as
    ``adapters`` that register nothing), sorted: discovered, never listed by hand."""
    import probecommit.tasks as package

    return sorted(m.name for m in pkgutil.iter_modules(package.__path__) if m.ispkg)


def default_family() -> str:
    """The family a config that names none runs: the one registered family whose spec says
    ``default=True`` (the paper's primary testbed); generic code never names it.

    Raises:
        UnknownTaskError: no family, or more than one, claims to be the default.
    """
    defaults = sorted(name for name, spec in families().items() if spec.default)
    if len(defaults) != 1:
        raise UnknownTaskError(f"a config must name its task family (task: NAME); default families registered: "
                               f"{', '.join(defaults) or 'none'}")
    return defaults[0]


def unregister(name: str) -> None:
    """Remove a family registered at run time (a test's, a notebook's); a no-op if absent."""
    _REGISTRY.pop(name, None)


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    for package in builtin_packages():
        importlib.import_module(f"probecommit.tasks.{package}")
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        # An entry point names a module (importing it registers), a TaskSpec, or a
        # callable returning one.
        loaded = ep.load()
        if callable(loaded) and not isinstance(loaded, (type, TaskSpec)):
            loaded = loaded()
        if isinstance(loaded, TaskSpec):
            register(loaded)


def families() -> dict[str, TaskSpec]:
    """Every registered family by name (built-ins and entry points)."""
    _load()
    return dict(_REGISTRY)


def get(name: str) -> TaskSpec:
    """The spec of family ``name``.

    Raises:
        UnknownTaskError: one line listing the registered families.
    """
    specs = families()
    if name not in specs:
        raise UnknownTaskError(f"unknown task family {name!r}; registered: {', '.join(sorted(specs))}")
    return specs[name]


def simulator_class(family: str, engine: str) -> type:
    """Import and return the simulator class of ``family`` in ``engine``.

    Raises:
        UnknownTaskError: the family lacks that engine (lists the engines it has).
        EngineUnavailableError: the engine is not installed (names the extra).
    """
    spec = get(family)
    if engine not in spec.simulators:
        raise UnknownTaskError(
            f"task family {family!r} has no {engine!r} simulator; it has: {', '.join(spec.engines)}"
        )
    entry = spec.simulators[engine]
    if isinstance(entry, type):  # a declared family's own analytic simulator, already a class
        return entry
    module_name, _, attr = entry.partition(":")
    module = importlib.import_module(module_name)
    return getattr(module, attr)


def build_simulator(family: str, task_config: Any) -> Any:
    """The ground-truth simulator of a family config (engine imported only here)."""
    cls = simulator_class(family, task_config.simulator.engine)
    kwargs = task_config.simulator_kwargs()
    simulator = cls(**kwargs)
    ignored = getattr(cls, "answer_independent_settings", ())
    shared = answer_store(family, task_config.simulator.engine, {k: v for k, v in kwargs.items() if k not in ignored})
    if shared is not None and hasattr(simulator, "shared_answers"):
        simulator.shared_answers = shared
    return simulator


def build_model(task_config: Any) -> Any:
    """The analytic model of a family config."""
    return get(task_config.family).build_model(task_config)
