"""The session log: append-only JSON Lines on disk, fsync'd per record, one writer at a time.

A robot's session is a sequence of records, one JSON object per line, each written
whole, flushed and ``fsync``'d before the call that made it returns: a crash (power
cut, SIGKILL) loses nothing a call already returned from. The first record is the
header (format, package version, the study config). Records are never rewritten.

A second process opening the same log for writing gets :class:`SessionLocked`,
naming the holder (an advisory ``flock`` on ``<log>.lock``, released by the OS when
the holder dies, so a crashed session can be reopened at once). A last line cut off
mid-write is reported with its line number; ``repair=True`` moves it, byte for byte,
to ``<log>.partial`` before appending again, so nothing is dropped silently.
"""

from __future__ import annotations

import json
import math
import os
import socket
import time
from pathlib import Path
from typing import Any, Iterator
from probecommit.errors import UserError

#: Format tag of the header record; bumped on an incompatible change.
LOG_FORMAT = "probecommit-session/1"
#: Record types, in the order a session writes them.
RECORD_TYPES = ("header", "episode", "observe", "decide", "outcome", "truth", "rejected", "note")
LOG_NAME = "session.jsonl"


def _lock_exclusive(fd: int) -> None:
    """An advisory exclusive lock on ``fd`` without waiting (BlockingIOError if held).

    ``fcntl`` is imported here, not at the top: it is POSIX only, and ``import
    probecommit.robot.session`` must work on Windows (where ``msvcrt`` locks a byte).
    """
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        try:
            os.lseek(fd, 0, os.SEEK_SET)
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            raise BlockingIOError("locked") from None
        return
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)


def _unlock(fd: int) -> None:
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)
        return
    fcntl.flock(fd, fcntl.LOCK_UN)


class SessionLogError(UserError, ValueError):
    """A session log is malformed; the message names the file and line."""


class SessionLocked(UserError, RuntimeError):
    """Another process holds the session log for writing; the message names it."""


def log_path(path: str | Path) -> Path:
    """The log file of ``path``: the path itself, or ``<dir>/session.jsonl`` for a directory."""
    path = Path(path)
    if path.is_dir() or (not path.suffix and not path.exists()):
        return path / LOG_NAME
    return path


def _finite(value: Any) -> Any:
    """JSON has no NaN: refuse one (a reading must be checked before it is logged)."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"cannot log a non-finite number {value!r}")
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def read_records(path: str | Path, *, allow_partial: bool = False) -> tuple[list[dict[str, Any]], bytes]:
    """Every record of a log, and the bytes of a cut-off last line (empty if none).

    Raises:
        SessionLogError: a line that is not a JSON object (naming it), a missing or
            foreign header, or (unless ``allow_partial``) a cut-off last line.
    """
    path = log_path(path)
    raw = path.read_bytes()
    partial = b""
    lines = raw.split(b"\n")
    if lines and lines[-1] != b"":
        partial = lines[-1]
    lines = lines[:-1]
    if partial and not allow_partial:
        raise SessionLogError(
            f"{path}: line {len(lines) + 1} was cut off mid-write ({len(partial)} bytes, no newline): the process "
            "stopped while writing it, so that call never returned. Reopen with repair=True (CLI: --repair) to move "
            f"it to {path.name}.partial and go on")
    records = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise SessionLogError(f"{path}: line {number} is not valid JSON ({exc.msg} at column {exc.colno})") from None
        if not isinstance(record, dict) or record.get("type") not in RECORD_TYPES:
            raise SessionLogError(f"{path}: line {number} is not a session record "
                                  f"(needs 'type' in {', '.join(RECORD_TYPES)})")
        record["_line"] = number
        records.append(record)
    if not records or records[0]["type"] != "header":
        raise SessionLogError(f"{path}: the first line must be the session header; this is not a probecommit session log")
    if records[0].get("format") != LOG_FORMAT:
        raise SessionLogError(f"{path}: header format {records[0].get('format')!r}, this version reads {LOG_FORMAT!r}")
    return records, partial


class SessionLog:
    """The writer of one session log (see the module docstring).

    Args:
        path: The log file (``.jsonl``) or a directory holding ``session.jsonl``.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = log_path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock_file = None
        self._file = None

    # ------------------------------------------------------------------ lock
    def acquire(self) -> None:
        """Take the writer's lock, or raise :class:`SessionLocked` naming the holder."""
        lock_path = self.path.with_name(self.path.name + ".lock")
        handle = open(lock_path, "a+")
        try:
            _lock_exclusive(handle.fileno())
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            handle.close()
            raise SessionLocked(f"{self.path} is open for writing by {holder}; one writer per log "
                                "(close that session, or wait for it to exit)") from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"pid {os.getpid()} on {socket.gethostname()} since {time.strftime('%Y-%m-%dT%H:%M:%S')}")
        handle.flush()
        self._lock_file = handle

    def release(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None
        if self._lock_file is not None:
            _unlock(self._lock_file.fileno())
            self._lock_file.close()
            self._lock_file = None

    # ------------------------------------------------------------------ writing
    def move_partial(self, partial: bytes) -> Path:
        """Move a cut-off last line to ``<log>.partial`` (appended, never overwritten) and truncate it."""
        side = self.path.with_name(self.path.name + ".partial")
        with open(side, "ab") as out:
            out.write(partial + b"\n")
            out.flush()
            os.fsync(out.fileno())
        size = self.path.stat().st_size
        with open(self.path, "r+b") as f:
            f.truncate(size - len(partial))
            f.flush()
            os.fsync(f.fileno())
        return side

    def append(self, record: dict[str, Any]) -> None:
        """Write one record as one line, flush and fsync before returning."""
        if self._lock_file is None:
            raise RuntimeError("the session log is not open for writing")
        record = {k: v for k, v in record.items() if not k.startswith("_")}
        line = json.dumps(_finite(record), separators=(",", ":"), allow_nan=False) + "\n"
        if self._file is None:
            self._file = open(self.path, "ab")
        self._file.write(line.encode())
        self._file.flush()
        os.fsync(self._file.fileno())

    def __enter__(self) -> "SessionLog":
        self.acquire()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.release()


def iter_type(records: list[dict[str, Any]], kind: str) -> Iterator[dict[str, Any]]:
    return (r for r in records if r["type"] == kind)
