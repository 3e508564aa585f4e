"""Run directories: config, manifest, Parquet tables, resumable shards.

Layout (the data contract users see)::

    runs/<name>/
      config.yaml          the exact validated config (seeds included)
      manifest.json        written last: versions, git commit, sha256 of each table
      instances.parquet    instance id, split, truth values
      probes.parquet       instance, repeat, j, probe u, observation y
      episodes.parquet     one row per (instance, repeat, budget, method)
      engine_cache.parquet every deterministic engine answer, so replays never re-run one
      shards/              per-unit partial results while a run is in progress

Every file is written to a temporary name and renamed into place, so a killed run
never leaves a half-written table; a directory without ``manifest.json`` is
incomplete by definition.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from probecommit import __version__

MANIFEST = "manifest.json"
CONFIG = "config.yaml"
TABLES = ("instances", "probes", "episodes", "engine_cache")


class RunDirError(RuntimeError):
    """A run directory is incomplete, incompatible or corrupt."""


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and an atomic rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_parquet(path: Path, frame: pd.DataFrame) -> None:
    sink = pa.BufferOutputStream()
    pq.write_table(pa.Table.from_pandas(frame, preserve_index=False), sink)
    atomic_write_bytes(path, sink.getvalue().to_pybytes())


def sha256_file(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def git_commit() -> str | None:
    """The package checkout's git commit, if it is one."""
    try:
        here = Path(__file__).resolve().parent
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5)
        return out.stdout.strip() or None
    except Exception:  # noqa: BLE001 - no git is fine
        return None


def engine_versions() -> dict[str, str | None]:
    from importlib import metadata

    out: dict[str, str | None] = {}
    for dist in ("mujoco", "pybullet", "sapien", "ray", "numpy"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


class RunDir:
    """A run directory on disk."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)

    @property
    def shards(self) -> Path:
        return self.path / "shards"

    def table_path(self, name: str) -> Path:
        return self.path / f"{name}.parquet"

    def is_complete(self) -> bool:
        return (self.path / MANIFEST).is_file()

    def prepare(self, config_yaml: str) -> None:
        """Create the directory, or accept it for resuming only if its config matches.

        Raises:
            RunDirError: the directory holds a run of another config or version.
        """
        cfg_path = self.path / CONFIG
        if cfg_path.is_file():
            existing = cfg_path.read_text()
            if existing != config_yaml:
                raise RunDirError(
                    f"{self.path} holds a run of a different config; refusing to mix results. "
                    "Choose another --out directory or delete it."
                )
            meta = self.path / "shards" / "VERSION"
            if meta.is_file() and meta.read_text().strip() != __version__:
                raise RunDirError(
                    f"{self.path} was started by probecommit {meta.read_text().strip()}, this is {__version__}; "
                    "refusing to mix results from two versions."
                )
            if self.is_complete():
                manifest = self.manifest()
                if manifest.get("probecommit_version") != __version__:
                    raise RunDirError(
                        f"{self.path} was written by probecommit {manifest.get('probecommit_version')}, "
                        f"this is {__version__}; refusing to mix results."
                    )
            return
        if self.path.exists() and any(self.path.iterdir()):
            raise RunDirError(f"{self.path} exists and is not a probecommit run directory; refusing to write into it")
        self.shards.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(self.shards / "VERSION", __version__.encode())
        atomic_write_bytes(cfg_path, config_yaml.encode())

    def config_text(self) -> str:
        return (self.path / CONFIG).read_text()

    def shard_path(self, unit: str, table: str) -> Path:
        return self.shards / f"{unit}.{table}.parquet"

    def unit_done(self, unit: str) -> bool:
        # The episodes shard is written last in a unit, so its presence means the unit is whole.
        return self.shard_path(unit, "episodes").is_file()

    def write_unit(self, unit: str, tables: dict[str, pd.DataFrame], stats: dict[str, Any]) -> None:
        for name in ("instances", "probes", "engine_cache"):
            atomic_write_parquet(self.shard_path(unit, name), tables[name])
        atomic_write_bytes(self.shards / f"{unit}.stats.json", json.dumps(stats).encode())
        atomic_write_parquet(self.shard_path(unit, "episodes"), tables["episodes"])

    def unit_stats(self, unit: str) -> dict[str, Any]:
        return json.loads((self.shards / f"{unit}.stats.json").read_text())

    def finalize(self, units: list[str], manifest_extra: dict[str, Any]) -> dict[str, Any]:
        """Merge unit shards in unit order into the final tables, then write the manifest."""
        digests = {}
        for name in TABLES:
            parts = [pd.read_parquet(self.shard_path(u, name)) for u in units]
            parts = [p for p in parts if len(p)]
            frame = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()
            if name == "episodes" and len(frame):
                # Canonical row order, independent of how instances were grouped into units.
                frame = frame.sort_values(["instance_id", "repeat"], kind="stable", ignore_index=True)
            atomic_write_parquet(self.table_path(name), frame)
            digests[f"{name}.parquet"] = sha256_file(self.table_path(name))
        manifest = {
            "probecommit_version": __version__,
            "git_commit": git_commit(),
            "engine_versions": engine_versions(),
            "sha256": digests,
            **manifest_extra,
        }
        atomic_write_bytes(self.path / MANIFEST, json.dumps(manifest, indent=2, sort_keys=True).encode())
        return manifest

    def manifest(self) -> dict[str, Any]:
        if not self.is_complete():
            raise RunDirError(f"{self.path} is not a complete run (no {MANIFEST}); rerun the same command to resume it")
        return json.loads((self.path / MANIFEST).read_text())

    def read(self, name: str) -> pd.DataFrame:
        self.manifest()
        return pd.read_parquet(self.table_path(name))

    def verify_digests(self) -> list[str]:
        """Tables whose sha256 no longer matches the manifest."""
        manifest = self.manifest()
        return [f for f, h in manifest["sha256"].items() if sha256_file(self.path / f) != h]
