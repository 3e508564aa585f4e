"""``key=value`` overrides of a study config and ``--sweep`` grids (Hydra's habit, pydantic's rules).

An override names a field of the flat config form by its dotted path
(``model.sigma=0.4``, ``instances.count=8``, ``simulator.engine=analytic``); the value
is read as YAML (``0.4`` a number, ``[1, 2]`` a list, ``true`` a bool). The overridden
mapping is validated by the same model as the file (:func:`parse_config`), so a typo
in a key or a bad value gets the same one-line error as in the YAML.
"""

from __future__ import annotations

import copy
import itertools
import re
from pathlib import Path
from typing import Any, Sequence

import yaml

from probecommit.errors import UsageError
from probecommit.store.yamlsafe import YamlError, load_yaml
from probecommit.runner.config import (ConfigError, StudyConfig, config_data, load_config, parse_config,
                                       read_config_data)

_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")

Override = tuple[str, Any]


def parse_override(item: str) -> Override:
    """``"model.sigma=0.4"`` -> ``("model.sigma", 0.4)``; the value is YAML."""
    key, eq, value = item.partition("=")
    key = key.strip()
    if not eq or not _KEY.match(key):
        raise UsageError(f"an override is KEY=VALUE with a dotted key (e.g. model.sigma=0.4), got {item!r}")
    try:  # the one bounded loader (size, aliases and merge keys, depth), as for --set and config files
        return key, load_yaml(value, f"override {key}") if value.strip() else None
    except YamlError:
        raise UsageError(f"override {key}: {value!r} is not a YAML value") from None


def parse_sweep(item: str) -> list[Override]:
    """``"model.sigma=0.3,0.5"`` -> one override per comma-separated value (each read as YAML)."""
    key, eq, values = item.partition("=")
    parts = [v for v in values.split(",")]
    if not eq or not values.strip() or any(not v.strip() for v in parts):
        raise UsageError(f"--sweep is KEY=A,B,C (e.g. model.sigma=0.3,0.5), got {item!r}")
    out = [parse_override(f"{key}={v.strip()}") for v in parts]
    if len({repr(v) for _, v in out}) != len(out):
        raise UsageError(f"--sweep {key.strip()} lists a value more than once: {values!r}")
    return out


def apply_overrides(data: dict[str, Any], overrides: Sequence[Override]) -> dict[str, Any]:
    """A copy of the flat config mapping ``data`` with each override set at its dotted path."""
    out = copy.deepcopy(data)
    for key, value in overrides:
        node = out
        parts = key.split(".")
        for depth, part in enumerate(parts[:-1]):
            child = node.get(part)
            if child is None:
                child = node[part] = {}
            if not isinstance(child, dict):
                raise UsageError(f"override {key}: {'.'.join(parts[:depth + 1])} is a value, not a section")
            node = child
        node[parts[-1]] = value
    return out


def load_with_overrides(path: str | Path, overrides: Sequence[Override]) -> StudyConfig:
    """The config file, then the overrides, validated together (one-line errors naming the field).

    The file's mapping takes the overrides before it is validated, so a run validates its
    config once; where that mapping cannot take them as written (the nested ``task: {...}``
    form, a section that is not a mapping), the file is validated first and the overrides
    applied to its flat form, as is every error's blame: a bad file is named alone.
    """
    if not overrides:
        return load_config(path)
    data = read_config_data(path)
    try:
        merged = None if isinstance(data.get("task"), dict) else apply_overrides(data, overrides)
    except UsageError:
        merged = None
    if merged is None:
        merged = apply_overrides(config_data(load_config(path)), overrides)
    try:
        return parse_config(merged)
    except ConfigError as exc:
        load_config(path)  # only on this error path: a bad file is named as the file's own error
        raise ConfigError(f"{path} with {' '.join(format_override(o) for o in overrides)}: {exc}") from None


def format_override(override: Override) -> str:
    """``("model.sigma", 0.4)`` -> ``"model.sigma=0.4"`` (the value as one-line YAML)."""
    key, value = override
    text = yaml.safe_dump(value, default_flow_style=True, width=10_000).strip()
    return f"{key}={text.removesuffix('...').strip()}"


def sweep_grid(sweeps: Sequence[Sequence[Override]]) -> list[list[Override]]:
    """Every combination of the swept values (the first sweep varies slowest)."""
    keys = [s[0][0] for s in sweeps]
    if len(set(keys)) != len(keys):
        raise UsageError(f"--sweep names a key twice: {', '.join(k for k in keys if keys.count(k) > 1)}")
    return [list(point) for point in itertools.product(*sweeps)]


def point_label(point: Sequence[Override]) -> str:
    """A run directory name for one sweep point: ``model.sigma=0.4,belief.particles=256``, with every
    character outside ``[A-Za-z0-9_.,=+-]`` replaced by ``_``."""
    return re.sub(r"[^A-Za-z0-9_.,=+-]", "_", ",".join(format_override(o) for o in point))
