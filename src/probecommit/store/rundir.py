"""Run directories: config, manifest, Parquet tables, resumable shards.

Layout (the data contract users see)::

    runs/<name>/
      config.yaml          the exact validated config (seeds included)
      manifest.json        written last: versions, git commit, sha256 of each table
      instances.parquet    instance id, split, truth values
      probes.parquet       instance, repeat, j, probe u, observation y
      episodes.parquet     one row per (instance, repeat, budget, method)
      engine_cache.parquet every deterministic engine answer, so replays never re-run one
      shards/              finished units, group-committed in batches (store/batches.py), each
                           marked with the code that wrote it (kept after completion)

Every file is written to a temporary name and renamed into place, so a killed run
never leaves a half-written table; a directory without ``manifest.json`` is
incomplete by definition. Finished units are committed a batch at a time (one fsync
per batch file and one of its directory), so a run resumes at batch granularity; every
batch carries the code identity that wrote it and a run refuses to join batches of
other code. The manifest is written after every final table. The final tables are in a canonical row order that does not depend
on how instances were grouped into units, on the backend or on the worker count.
A replay (one unit, nothing to resume) writes its final tables directly instead: the
source's instances and probes copied, its episodes a chunk at a time
(:class:`EpisodeStream`), its engine cache from Arrow tables.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import subprocess
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from probecommit import __version__
from probecommit.store.manifest_rules import ManifestError, read_manifest, sha256_file
from probecommit.store.safefile import atomic_file
from probecommit.store.yamlsafe import YamlError, load_yaml
from probecommit.store import batches
from probecommit.store.arrow_columns import column_array, indices, pandas_metadata
from probecommit.store.canonical import (by_instance, canonical_arrow, engine_cache_order, instance_order,
                                         instance_positions, merge_arrow, with_schema_columns)
from probecommit.store.schema import EPISODE_COLUMNS, INSTANCE_COLUMNS, PROBE_COLUMNS, Column, vector_columns
from probecommit.errors import UserError

if TYPE_CHECKING:
    import pandas as pd

MANIFEST = "manifest.json"
CONFIG = "config.yaml"
VERSION = "VERSION"
#: Hash of the package source that started an unfinished run (a resume must match it).
CODE = "CODE"
LOCK = "LOCK"
TABLES = ("instances", "probes", "episodes", "engine_cache")
_SCHEMAS: dict[str, tuple[Column, ...]] = {
    "instances": INSTANCE_COLUMNS,
    "probes": PROBE_COLUMNS,
    "episodes": EPISODE_COLUMNS,
}


class RunDirError(UserError, RuntimeError):
    """A run directory is incomplete, incompatible or corrupt."""


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and an atomic rename."""
    with atomic_file(path) as fh:
        fh.write(data)


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (POSIX: the directory entry is data of its own)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - a platform without directory descriptors
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - some filesystems refuse fsync on a directory
        pass
    finally:
        os.close(fd)


def merge_tables(tables: list[pa.Table]) -> "pd.DataFrame":
    """:func:`~probecommit.store.canonical.merge_arrow` as a DataFrame (what ``pd.concat`` of each
    table converted alone gives)."""
    import pandas as pd

    merged = merge_arrow(tables)
    return pd.DataFrame() if merged is None else merged.to_pandas()


def _empty_table() -> pa.Table:
    """The table of no units (an empty DataFrame converted, as it always was)."""
    import pandas as pd

    return pa.Table.from_pandas(pd.DataFrame(), preserve_index=False)


def _is_tmp(path: Path) -> bool:
    return path.name.startswith(".") and path.name.endswith(".tmp")


def arrow_table(frame: pd.DataFrame, columns: tuple[Column, ...] = ()) -> pa.Table:
    """``frame`` as the Arrow table a run file holds: columns named in ``columns`` get their schema type."""
    # One thread: for a long table pyarrow would start (and join) a thread pool per call.
    return _schema_typed(pa.Table.from_pandas(frame, preserve_index=False, nthreads=1), columns)


def _schema_typed(table: pa.Table, columns: tuple[Column, ...]) -> pa.Table:
    """``table`` with the columns named in ``columns`` cast to their schema type."""
    types = {c.name: c.type for c in columns}
    for c in columns:
        if c.vector:  # u_0, u_1, ... take the type of u
            types.update({name: c.type for name in vector_columns(table.schema.names, c.name)})
    if types:
        target = pa.schema([pa.field(f.name, types.get(f.name, f.type)) for f in table.schema])
        if target != table.schema:
            table = table.cast(target)
    return table


#: pandas metadata of tables built by :func:`arrow_from_columns`, by column names and types.
_PANDAS_METADATA: dict[tuple, dict[bytes, bytes] | None] = {}


def arrow_from_columns(columns: dict[str, Any], n_rows: int, schema: tuple[Column, ...] = ()) -> pa.Table:
    """The table ``arrow_table(pd.DataFrame(columns), schema)`` gives, built without a DataFrame.

    ``columns`` maps names to 1-D NumPy arrays or lists of ``n_rows`` values, or to scalars
    (broadcast). Converted as ``from_pandas`` converts them (NaN is null; strings are large
    strings) and with the same pandas metadata (made once per column names and types, as a
    one-row frame gives it), so the merge reads back the same frame; tested against ``arrow_table``.
    A unit's tables are built this way: a DataFrame per table per unit cost more than the
    unit's beliefs on a short study. The columns and metadata are built from buffers, without
    pandas (``store/arrow_columns.py``); a column of a kind it does not build goes through
    pyarrow's inference and pandas' metadata, which import pandas.
    """
    if not columns or not n_rows:  # pandas decides an empty column's type: ask it (cheap when empty)
        import pandas as pd

        return arrow_table(pd.DataFrame(columns), schema)
    arrays = [column_array(value, n_rows) for value in columns.values()]
    if any(array is None for array in arrays):  # a kind arrow_columns does not build: through pyarrow's inference
        arrays = [_inferred_array(value, n_rows) for value in columns.values()]
    names = list(columns)
    key = tuple(zip(names, (a.type for a in arrays)))
    if key not in _PANDAS_METADATA:
        _PANDAS_METADATA[key] = pandas_metadata(columns, arrays) or _sampled_metadata(columns)
    table = pa.Table.from_arrays(arrays, names=names).replace_schema_metadata(_PANDAS_METADATA[key])
    return _schema_typed(table, schema)


def _inferred_array(value: Any, n_rows: int) -> pa.Array:
    """``value`` through ``pa.array(from_pandas=True)`` (which imports pandas), strings as large strings."""
    if not isinstance(value, (list, np.ndarray)):  # a scalar
        value = np.broadcast_to(np.asarray(value), (n_rows,))
        if value.dtype.kind == "U":
            value = value.astype(object)
    if isinstance(value, np.ndarray) and value.dtype.kind == "U":  # strings: large, as pandas' str dtype gives
        return pa.array(value, type=pa.large_string())
    array = pa.array(value, from_pandas=True)
    return array.cast(pa.large_string()) if pa.types.is_string(array.type) else array


def _sampled_metadata(columns: dict[str, Any]) -> dict[bytes, bytes] | None:
    """The pandas metadata of a one-row DataFrame of the columns' first values, asked of pandas."""
    import pandas as pd

    sample = pd.DataFrame({name: (value[:1] if isinstance(value, (list, np.ndarray)) else value)
                           for name, value in columns.items()}, index=range(1))
    return pa.Schema.from_pandas(sample, preserve_index=False).metadata


def atomic_write_parquet(path: Path, frame: pd.DataFrame, columns: tuple[Column, ...] = ()) -> pa.Table:
    """Write a table atomically; columns named in ``columns`` get their schema type.

    Returns:
        The Arrow table written (what reading the file back gives).
    """
    table = arrow_table(frame, columns)
    atomic_write_arrow(path, table)
    return table


def atomic_write_arrow(path: Path, table: pa.Table) -> None:
    """Write an Arrow table to ``path`` as Parquet, atomically."""
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    atomic_write_bytes(path, sink.getvalue().to_pybytes())


def flatten_dotted(data: Any, prefix: str = "") -> dict[str, Any]:
    """Every leaf of nested dicts (a config, a ``results.json``) by its dotted path: what two of them are
    compared by, field by field (lists are leaves)."""
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            out.update(flatten_dotted(value, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): data}


def config_difference(old_yaml: str, new_yaml: str) -> str:
    """The first differing config field, as ``field: old in the directory, new here``."""
    try:
        old = flatten_dotted(load_yaml(old_yaml, "config.yaml") or {})
        new = flatten_dotted(load_yaml(new_yaml, "the config") or {})
    except YamlError:
        return "its config.yaml is not valid YAML"
    for key in list(new) + [k for k in old if k not in new]:
        if old.get(key, "<unset>") != new.get(key, "<unset>"):
            return f"{key} is {old.get(key, '<unset>')!r} there, {new.get(key, '<unset>')!r} here"
    return "the config text differs"


def git_commit() -> str | None:
    """The package checkout's git commit, if it is one."""
    try:
        here = Path(__file__).resolve().parent
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5)
        return out.stdout.strip() or None
    except Exception:  # noqa: BLE001 - no git is fine
        return None


_CODE_IDENTITY: str | None = None


def code_identity() -> str:
    """sha256 of the package's Python source (every ``.py`` under ``probecommit/``, path and bytes).

    Two builds with the same ``__version__`` but different code differ here, so an
    unfinished run is never resumed by other code than the one that started it.
    """
    global _CODE_IDENTITY
    if _CODE_IDENTITY is None:
        root = Path(__file__).resolve().parents[1]
        digest = hashlib.sha256()
        for path in sorted(root.rglob("*.py")):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
        _CODE_IDENTITY = digest.hexdigest()
    return _CODE_IDENTITY


def git_dirty() -> bool | None:
    """Whether the package checkout has uncommitted changes (None outside a git checkout)."""
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here, capture_output=True,
                             text=True, timeout=5)
        return bool(out.stdout.strip()) if out.returncode == 0 else None
    except Exception:  # noqa: BLE001 - no git is fine
        return None


def provenance() -> tuple[str | None, bool | None, dict[str, str | None]]:
    """What a manifest records of where a run came from: git commit, uncommitted changes, versions."""
    return git_commit(), git_dirty(), engine_versions()


class _InBackground:
    """A function's value computed in a thread of its own, taken (the thread joined) when needed.

    A run's provenance (two ``git`` processes and a scan of the installed packages' metadata:
    tens of milliseconds) is looked up while its units compute, not after them.
    """

    def __init__(self, fn: Any) -> None:
        import threading

        self._value: Any = None
        self._error: BaseException | None = None

        def target() -> None:
            try:
                self._value = fn()
            except BaseException as exc:  # noqa: BLE001 - raised where the value is taken
                self._error = exc

        self._thread = threading.Thread(target=target, name="probecommit-provenance", daemon=True)
        self._thread.start()

    def result(self) -> Any:
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value


def engine_versions() -> dict[str, str | None]:
    """Python's version and those of the engines and the data stack, as the manifest records them
    (None: not installed)."""
    import platform
    from importlib import metadata

    out: dict[str, str | None] = {"python": platform.python_version()}
    for name in ("mujoco", "pybullet", "sapien", "ray", "numpy", "pandas", "pyarrow", "numba"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


class RunDir:
    """A run directory on disk."""

    #: Shard tables this object wrote are kept for the merge up to this many bytes in all
    #: (the merge then converts them instead of reading and decoding the files again).
    KEEP_WRITTEN_BYTES = 64 * 2**20
    #: A batch is committed at this many units, bytes of tables or seconds since the last one
    #: (a kill loses at most that much work); ``$PROBECOMMIT_BATCH_UNITS`` and
    #: ``$PROBECOMMIT_BATCH_SECONDS`` override the first and the last.
    batch_units = int(os.environ.get("PROBECOMMIT_BATCH_UNITS", "256"))
    batch_bytes = 64 * 2**20
    batch_seconds = float(os.environ.get("PROBECOMMIT_BATCH_SECONDS", "2"))

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._kept: dict[str, dict[str, pa.Table]] = {}
        self._kept_bytes = 0
        self._pending: list[tuple[str, dict[str, pa.Table], dict[str, Any]]] = []
        self._pending_bytes = 0
        self._pending_sizes: dict[str, int] = {}
        self._written_episodes: pa.Table | None = None  # the final episodes table, once finalize wrote it
        self._last_commit = time.monotonic()
        self._batches: dict[str, Path] = {}
        self._stats: dict[str, dict[str, Any]] = {}
        self._provenance: _InBackground | None = None

    @property
    def shards(self) -> Path:
        return self.path / "shards"

    def table_path(self, name: str) -> Path:
        return self.path / f"{name}.parquet"

    def is_complete(self) -> bool:
        return (self.path / MANIFEST).is_file()

    def check_compatible(self, config_yaml: str) -> None:
        """Refuse a directory written by another probecommit version or of another config.

        Versions are checked first (a new version may also change the config's
        defaults, and the version is then the real reason).

        Raises:
            RunDirError: naming the version or the first differing config field.
        """
        hint = "choose another --out directory, or delete this one to start over"
        meta = self.shards / VERSION
        if meta.is_file() and meta.read_text().strip() != __version__:
            raise RunDirError(
                f"{self.path} was started by probecommit {meta.read_text().strip()}, this is {__version__}; "
                f"refusing to mix results from two versions ({hint})"
            )
        code = self.shards / CODE
        if not self.is_complete() and (self.path / CONFIG).is_file() and self.shards.is_dir():
            started = code.read_text().strip() if code.is_file() else "unrecorded"
            if started != code_identity():
                raise RunDirError(
                    f"{self.path} is an unfinished run started by other code (package source {started[:12]}, this is "
                    f"{code_identity()[:12]}, same version {__version__}); resuming would mix results from two builds. "
                    f"Start fresh: delete {self.path} (or choose another --out) and rerun the same command"
                )
        if self.is_complete():
            try:
                written_by = json.loads((self.path / MANIFEST).read_text()).get("probecommit_version")
            except (ValueError, AttributeError):
                raise RunDirError(f"{self.path}/{MANIFEST} is not valid JSON; the directory is corrupt ({hint})") from None
            if written_by != __version__:
                raise RunDirError(
                    f"{self.path} was written by probecommit {written_by}, this is {__version__}; "
                    f"refusing to mix results from two versions ({hint})"
                )
        self._check_batch_code()
        existing = (self.path / CONFIG).read_text()
        if existing != config_yaml:
            raise RunDirError(
                f"{self.path} holds a run of a different config ({config_difference(existing, config_yaml)}); "
                f"refusing to mix results ({hint})"
            )

    def _ours_but_unstarted(self) -> bool:
        """A directory a killed run left before it wrote its config: nothing but shards/VERSION."""
        entries = [e for e in self.path.iterdir() if not _is_tmp(e)]
        if [e.name for e in entries] != ["shards"] or not self.shards.is_dir():
            return False
        return all(e.name in (VERSION, CODE, LOCK) or _is_tmp(e) for e in self.shards.iterdir())

    def check_writable(self, config_yaml: str) -> None:
        """Read-only checks that this run may be started or resumed here; creates nothing.

        Raises:
            RunDirError: the directory holds a run of another config or version, or
                something that is not a run directory.
        """
        if (self.path / CONFIG).is_file():
            self.check_compatible(config_yaml)
            return
        if self.path.exists() and not self.path.is_dir():
            raise RunDirError(f"{self.path} exists and is not a directory; refusing to write into it")
        if self.path.exists() and any(self.path.iterdir()) and not self._ours_but_unstarted():
            raise RunDirError(f"{self.path} exists and is not a probecommit run directory; refusing to write into it")

    def prepare(self, config_yaml: str) -> None:
        """Create the directory, or accept it for resuming only if it is compatible.

        Call with :meth:`lock` held when another process could write the directory
        (see :meth:`writing`): it deletes temporaries a killed writer left.

        Raises:
            RunDirError: as :meth:`check_writable`.
        """
        self.check_writable(config_yaml)
        cfg_path = self.path / CONFIG
        self.shards.mkdir(parents=True, exist_ok=True)
        self.remove_stale_temporaries()
        if not cfg_path.is_file() or not (self.shards / VERSION).is_file():
            # VERSION first: a directory with a config but without VERSION was killed in
            # between and has no unit yet, so writing VERSION now mixes nothing.
            atomic_write_bytes(self.shards / VERSION, __version__.encode())
            atomic_write_bytes(self.shards / CODE, code_identity().encode())
        if not cfg_path.is_file():
            atomic_write_bytes(cfg_path, config_yaml.encode())

    @contextlib.contextmanager
    def writing(self, config_yaml: str) -> Iterator[None]:
        """Check, lock and prepare the directory for a run, and hold the lock throughout."""
        self.check_writable(config_yaml)
        with self.lock():
            self.prepare(config_yaml)
            self._provenance = _InBackground(provenance)  # for the manifest, looked up meanwhile
            try:
                yield
            finally:
                with contextlib.suppress(Exception):  # its thread ends with the run, not after it
                    self._provenance.result()
                self._provenance = None

    def remove_stale_temporaries(self) -> None:
        """Delete temporary files a killed writer left behind (call with the lock held)."""
        for folder in (self.path, self.shards):
            if folder.is_dir():
                for entry in folder.iterdir():
                    if _is_tmp(entry) and entry.is_file():
                        entry.unlink(missing_ok=True)

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold an exclusive lock on the directory while writing it.

        The operating system releases it when the process dies, SIGKILL included,
        so a killed run never blocks its own resumption.

        Raises:
            RunDirError: another live process is writing this directory.
        """
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            yield
            return
        self.shards.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.shards / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                raise RunDirError(
                    f"{self.path} is being written by another probecommit process; wait for it or stop it first"
                ) from None
            yield
        finally:
            os.close(fd)

    def config_text(self) -> str:
        return (self.path / CONFIG).read_text()

    # ---- group-committed shard batches (see store/batches.py) -------------------------------

    def _batch_paths(self) -> list[Path]:
        if not self.shards.is_dir():
            return []
        found = [(batches.batch_index(p), p) for p in self.shards.iterdir()]
        return [p for n, p in sorted((n, p) for n, p in found if n is not None)]

    def done_units(self) -> set[str]:
        """The units stored in this directory's batches (call with the lock held).

        Every batch is read and checked: one that is not a whole, unaltered batch is deleted
        (its units run again); one written by other code than this is refused, as are
        per-unit shards of the earlier layout, which record no code identity. So a resumed
        or rebuilt run never joins results of two builds.

        Raises:
            RunDirError: one line naming both code identities.
        """
        self._batches, self._stats = {}, {}
        legacy = sorted(p.name for p in self.shards.glob("unit-*")) if self.shards.is_dir() else []
        if legacy:
            raise self._other_code(legacy[0], "unrecorded (a shard of the earlier per-unit layout)")
        for path in self._batch_paths():
            try:
                header, stored = batches.read(path)
            except (batches.BatchError, OSError, pa.ArrowException, KeyError, TypeError, ValueError):
                path.unlink(missing_ok=True)  # cut short or altered: its units run again
                continue
            if header.get("code") != code_identity():
                raise self._other_code(path.name, str(header.get("code")))
            for entry in header["units"]:
                if entry["unit"] not in self._batches:
                    self._batches[entry["unit"]] = path
                    self._stats[entry["unit"]] = entry["stats"]
                    self._keep(entry["unit"], stored[entry["unit"]])  # finalize need not decode it again
        code = self.shards / CODE
        if self.shards.is_dir() and (not code.is_file() or code.read_text().strip() != code_identity()):
            # Only a complete run gets here with another CODE (an unfinished one is refused by
            # check_compatible): its batches are all this code's, so the rebuild is too.
            atomic_write_bytes(code, code_identity().encode())
        self._next_batch = 1 + max((batches.batch_index(p) or 0 for p in self._batch_paths()), default=-1)
        return set(self._batches)

    def _check_batch_code(self) -> None:
        """Read-only: refuse batches of other code (or shards of the earlier layout) before any
        work starts; headers only (:meth:`done_units` checks every batch whole, with the lock)."""
        legacy = sorted(p.name for p in self.shards.glob("unit-*")) if self.shards.is_dir() else []
        if legacy:
            raise self._other_code(legacy[0], "unrecorded (a shard of the earlier per-unit layout)")
        for path in self._batch_paths():
            try:
                code = batches.read_header(path).get("code")
            except (batches.BatchError, OSError):
                continue  # a damaged batch: deleted and redone by done_units
            if code != code_identity():
                raise self._other_code(path.name, str(code))

    def _other_code(self, name: str, other: str) -> RunDirError:
        return RunDirError(
            f"{self.path}: shards/{name} was written by other code (package source {other[:12]}), this is "
            f"{code_identity()[:12]}; a run never mixes two builds: delete {self.path} (or choose another --out) "
            f"and rerun the same command"
        )

    def unit_done(self, unit: str) -> bool:
        """Whether ``unit`` is stored in a batch (see :meth:`done_units`)."""
        return unit in self.done_units()

    def add_unit(self, unit: str, tables: dict[str, "pd.DataFrame | pa.Table"], stats: dict[str, Any],
                 commit: bool = True) -> None:
        """Queue a finished unit; with ``commit``, the batch is committed (one durable write) when
        it is due (:meth:`commit_if_due`). Call :meth:`flush` (``finalize`` does) to commit the rest."""
        arrow = {name: t if isinstance(t, pa.Table) else arrow_table(t, _SCHEMAS.get(name, ()))
                 for name, t in tables.items()}
        self._pending.append((unit, arrow, stats))
        # Measured once, here, and reused when the unit is kept: a slice's nbytes walks every
        # column's buffers (~0.1 ms a unit table), and a run has a few hundred unit tables.
        self._pending_sizes[unit] = size = sum(t.nbytes for t in arrow.values())
        self._pending_bytes += size
        if commit:
            self.commit_if_due()

    def commit_if_due(self) -> None:
        """Commit the queued units if the batch is due: ``batch_units`` units, ``batch_bytes`` of
        tables or ``batch_seconds`` since the last commit."""
        if (len(self._pending) >= self.batch_units or self._pending_bytes >= self.batch_bytes
                or time.monotonic() - self._last_commit >= self.batch_seconds):
            self.flush()

    def flush(self) -> None:
        """Commit the queued units as one batch: a temporary file, one fsync, a rename and an
        fsync of ``shards/``."""
        if not self._pending:
            return
        if not hasattr(self, "_next_batch"):
            self.done_units()
        path = self.shards / batches.batch_name(self._next_batch)
        atomic_write_bytes(path, batches.encode(self._pending, code_identity(), __version__))
        _fsync_dir(self.shards)
        self._next_batch += 1
        for unit, tables, stats in self._pending:
            self._batches[unit], self._stats[unit] = path, stats
            self._keep(unit, tables, self._pending_sizes.pop(unit, None))
        self._pending, self._pending_bytes, self._last_commit = [], 0, time.monotonic()

    def _keep(self, unit: str, tables: dict[str, pa.Table], size: int | None = None) -> None:
        """Hold a stored unit's tables for the merge while they fit ``KEEP_WRITTEN_BYTES`` (written
        by this object, or decoded by :meth:`done_units` on resume), so no batch is decoded twice.
        ``size``: the tables' bytes when already measured (:meth:`add_unit`)."""
        if unit in self._kept:
            return
        size = sum(t.nbytes for t in tables.values()) if size is None else size
        if self._kept_bytes + size <= self.KEEP_WRITTEN_BYTES:
            self._kept[unit] = tables
            self._kept_bytes += size

    def unit_stats(self, unit: str) -> dict[str, Any]:
        return self._stats[unit]

    def _unit_tables(self, units: list[str]) -> dict[str, dict[str, pa.Table]]:
        """Every unit's tables: the ones this object committed, if kept, else read (and checked)
        from their batch, each batch once."""
        out = {u: self._kept.pop(u) for u in units if u in self._kept}
        self._kept_bytes = sum(t.nbytes for tables in self._kept.values() for t in tables.values())
        for path in dict.fromkeys(self._batches[u] for u in units if u not in out):
            try:
                _, stored = batches.read(path)
            except batches.BatchError as exc:
                raise RunDirError(f"{self.path}: {exc}; rerun the same command to redo its units") from None
            out.update({u: t for u, t in stored.items() if u in units and u not in out})
        return out

    def finalize(self, units: list[str], manifest_extra: dict[str, Any]) -> dict[str, Any]:
        """Merge the units' tables into the final tables (canonical order), then write the manifest."""
        self.flush()
        stored = self._unit_tables(units)
        merged = {name: merge_arrow([stored[u][name] for u in units]) for name in TABLES}
        del stored
        for name, table in canonical_arrow(merged, _SCHEMAS).items():
            table = _schema_typed(table if table is not None else _empty_table(), _SCHEMAS.get(name, ()))
            atomic_write_arrow(self.table_path(name), table)
            if name == "episodes":
                self._written_episodes = table
        return self.write_manifest(manifest_extra)

    def final_episodes_table(self) -> pa.Table:
        """The final episodes table as an Arrow table: the one :meth:`finalize` wrote when this object
        wrote it (a run does not read back and decode the file it just wrote), else read from the file
        (``ParquetFile``: ``pq.read_table`` imports the dataset layer, and with it pandas). Its
        ``to_pandas()`` is what ``pd.read_parquet`` of the file gives."""
        table = self._written_episodes
        return pq.ParquetFile(self.table_path("episodes")).read() if table is None else table

    def copy_table(self, source: "RunDir", name: str) -> None:
        """Final table ``name`` of another complete run, as it is (checked against its manifest)."""
        atomic_write_bytes(self.table_path(name), source._verified_bytes(name))

    def episode_stream(self, instances: pd.DataFrame, pending: pd.DataFrame | None = None) -> "EpisodeStream":
        """A writer of the final episodes table a part at a time (see :class:`EpisodeStream`); as a
        context manager, it finishes the table when its block ends, or drops the parts if it raised."""
        return EpisodeStream(self, instances, pending)

    def write_engine_cache(self, table: pa.Table) -> None:
        """The final engine cache from an Arrow table of answers (each once), put in canonical order."""
        rows = engine_cache_order(table)
        atomic_write_arrow(self.table_path("engine_cache"), table if rows is None else table.take(indices(rows)))

    def write_manifest(self, manifest_extra: dict[str, Any]) -> dict[str, Any]:
        """The manifest, written last: versions and the sha256 of every final table and the config."""
        digests = {f"{name}.parquet": sha256_file(self.table_path(name)) for name in TABLES}
        digests[CONFIG] = sha256_file(self.path / CONFIG)  # a hand-edited config is caught on read
        commit, dirty, versions = provenance() if self._provenance is None else self._provenance.result()
        manifest = {
            "probecommit_version": __version__,
            "git_commit": commit,
            "git_dirty": dirty,
            "code_sha256": code_identity(),
            "engine_versions": versions,
            "sha256": digests,
            **manifest_extra,
        }
        atomic_write_bytes(self.path / MANIFEST, json.dumps(manifest, indent=2, sort_keys=True).encode())
        return manifest

    def manifest(self) -> dict[str, Any]:
        if not self.is_complete():
            raise RunDirError(f"{self.path} is not a complete run (no {MANIFEST}); rerun the same command to resume it")
        try:  # the manifest rule set: a JSON object with a non-empty sha256 map, named on error
            return read_manifest(self.path / MANIFEST)
        except ManifestError as exc:
            raise RunDirError(str(exc)) from None

    def read(self, name: str) -> pd.DataFrame:
        import pandas as pd

        self.manifest()
        return pd.read_parquet(self.table_path(name))

    def read_verified(self, name: str, where: tuple[str, list] | None = None,
                      columns: Sequence[str] | None = None) -> pd.DataFrame:
        """A final table whose bytes still match the manifest's sha256, optionally only its rows
        whose column ``where[0]`` takes one of the values ``where[1]`` (read with that filter) and
        only the ``columns`` named.

        Raises:
            RunDirError: The file changed since the run wrote its manifest.
        """
        import pandas as pd

        filters = None if where is None else [(where[0], "in", list(where[1]))]
        return pd.read_parquet(self._verified_source(name), filters=filters,
                               columns=None if columns is None else list(columns))

    def read_verified_arrow(self, name: str) -> pa.Table:
        """:meth:`read_verified` as an Arrow table: columns in a few buffers, no Python object per
        row (what a replay holds of a run's engine answers while it works chunk by chunk)."""
        return pq.read_table(self._verified_source(name))

    def _verified_source(self, name: str) -> pa.BufferReader:
        """The verified bytes of table ``name`` as an Arrow buffer to read Parquet from.

        Why not ``io.BytesIO``: Arrow reads a Python file object through the interpreter from its own
        I/O and CPU threads (a scan's read-ahead may still be running when the read returns). A
        command that exits just after such a read (a replay prints its new run's table last) can
        finalize the interpreter while an Arrow thread waits for the GIL; CPython then ends that
        thread with ``pthread_exit``, whose forced unwind through Arrow's C++ frames calls
        ``std::terminate``: SIGABRT, "terminate called without an active exception". From an
        Arrow buffer no Arrow thread ever enters the interpreter.
        """
        return pa.BufferReader(self._verified_bytes(name))

    def _verified_bytes(self, name: str) -> bytes:
        """The bytes of final table ``name``, refused when they no longer match the manifest's sha256."""
        manifest = self.manifest()
        data = self.table_path(name).read_bytes()
        if hashlib.sha256(data).hexdigest() != manifest["sha256"].get(f"{name}.parquet"):
            raise self.altered([f"{name}.parquet"])
        return data

    def altered(self, files: list[str]) -> RunDirError:
        """The error for files that no longer match the manifest's sha256."""
        return RunDirError(f"{self.path}: {', '.join(files)} changed since the run wrote its manifest (sha256 "
                           "differs); refusing to read an altered run")

    def verify_digests(self) -> list[str]:
        """Tables whose sha256 no longer matches the manifest."""
        manifest = self.manifest()
        listed = manifest["sha256"]
        # Integrity on read: every file a reader uses must be listed (an emptied map proves nothing).
        unlisted = [f"{f} (not in the manifest)" for f in (*(f"{t}.parquet" for t in TABLES), CONFIG)
                    if f not in listed and (self.path / f).exists()]
        return unlisted + [f for f, h in listed.items()
                           if not (self.path / f).is_file() or sha256_file(self.path / f) != h]


class EpisodeStream:
    """A run's final episodes table, written a part at a time without the whole table in memory
    (a replay writes each chunk's episodes when the chunk is done).

    Parts come in the canonical instance order: each part's instances follow the previous
    part's, as a replay's chunks do; within a part, rows are put in canonical order. Rows known
    beforehand (``pending``: a run's failed rollouts) each go into the first part that reaches
    their instance's position, or into the last. Each part is written to a temporary file in
    ``shards/``; :meth:`finish` joins them into ``episodes.parquet``, a part at a time, each with
    the column types of all parts together (a column that one part lacks is null there), and
    removes them (as does a ``with`` block that raises). The table read back equals the one
    :meth:`RunDir.finalize` writes of the parts' rows together (tested).

    Args:
        run: The run directory (prepared).
        instances: Its instances table (their canonical order).
        pending: Rows to place among the parts' (None: none).
    """

    def __init__(self, run: RunDir, instances: pd.DataFrame, pending: pd.DataFrame | None = None) -> None:
        self.run = run
        self._order = instance_order(pa.Table.from_pandas(instances, preserve_index=False, nthreads=1))
        self._pending = pending if pending is not None and len(pending) else None
        self._pending_at = None if self._pending is None else _instance_positions(self._pending, self._order)
        self._parts: list[Path] = []
        self._reached = -np.inf

    def add(self, frame: pd.DataFrame) -> None:
        """Write the next part (a frame of episode rows)."""
        if len(frame) and "instance_id" in frame.columns:
            at = _instance_positions(frame, self._order)
            if at.min() < self._reached:
                raise ValueError("episode parts must come in instance order: this part has an instance "
                                 "before the previous part's last")
            self._reached = at.max()
            if self._pending is not None:
                take = self._pending_at <= self._reached
                if take.any():
                    import pandas as pd

                    frame = pd.concat([frame, self._pending[take]], ignore_index=True)
                    self._pending, self._pending_at = self._pending[~take], self._pending_at[~take]
        self._write_part(frame)

    def _write_part(self, frame: pd.DataFrame) -> None:
        table = pa.Table.from_pandas(frame, preserve_index=False, nthreads=1)
        table = with_schema_columns(by_instance(table, ["instance_id", "repeat"], self._order), EPISODE_COLUMNS)
        # A temporary's name: a killed writer's parts go with remove_stale_temporaries.
        path = self.run.shards / f".episodes.part{len(self._parts):06d}.parquet.tmp"
        self.run.shards.mkdir(parents=True, exist_ok=True)
        pq.write_table(_schema_typed(table, EPISODE_COLUMNS), path)
        self._parts.append(path)

    def __enter__(self) -> "EpisodeStream":
        return self

    def __exit__(self, kind, value, traceback) -> None:
        """:meth:`finish` when the block ends without error; otherwise only the parts go."""
        if kind is None:
            self.finish()
        else:
            self._discard()

    def finish(self) -> None:
        """Write ``episodes.parquet`` from the parts (and the pending rows no part reached)."""
        import pandas as pd

        if self._pending is not None and len(self._pending):
            # Rows no part reached join the last part (read back), not a part of their own, which
            # would lack the columns only episode rows have (a vector action's components).
            last = [pd.read_parquet(self._parts.pop())] if self._parts else []
            self._write_part(pd.concat([*last, self._pending], ignore_index=True))
        self._pending = None
        path = self.run.table_path("episodes")
        try:
            if not self._parts:
                atomic_write_parquet(path, pd.DataFrame(), EPISODE_COLUMNS)
                return
            schema = pa.unify_schemas([pq.read_schema(part) for part in self._parts], promote_options="permissive")
            with atomic_file(path) as fh, pq.ParquetWriter(fh, schema) as writer:
                for part in self._parts:
                    writer.write_table(_conformed(pq.read_table(part), schema))
        finally:
            self._discard()

    def _discard(self) -> None:
        for part in self._parts:
            part.unlink(missing_ok=True)
        self._parts = []


def _conformed(table: pa.Table, schema: pa.Schema) -> pa.Table:
    """``table`` with ``schema``'s columns, in its order and of its types (null where it has none)."""
    for field in schema:
        if field.name not in table.column_names:
            table = table.append_column(field.name, pa.nulls(table.num_rows, field.type))
    return table.select(schema.names).cast(schema)


def canonical_tables(frames: dict[str, "pd.DataFrame | None"]) -> dict[str, "pd.DataFrame | None"]:
    """:func:`~probecommit.store.canonical.canonical_arrow` of DataFrames (the schema's tables get
    their columns), as DataFrames."""
    tables = {name: None if f is None else pa.Table.from_pandas(f, preserve_index=False, nthreads=1)
              for name, f in frames.items()}
    return {name: None if t is None else t.to_pandas() for name, t in canonical_arrow(tables, _SCHEMAS).items()}


def _instance_positions(frame: Any, order: dict[str, int]) -> np.ndarray:
    """Each row's instance position in ``order`` (:func:`~probecommit.store.canonical.instance_positions`
    of its ``instance_id`` column); ids it lacks come after every instance."""
    return instance_positions(frame["instance_id"], order)
