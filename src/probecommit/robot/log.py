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

import errno
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


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows (a reading must be finite)")


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            and abs(v) <= MAX_MAGNITUDE)


#: Largest magnitude of a number in a record (beyond it a value is a unit or parse error).
MAX_MAGNITUDE = 1e12

#: The field rules of each record type: field -> (check, what it must be). Fields not named
#: are free (``t``, ``notes``, ``decide_s``, a rejected call's raw inputs).
_NUMS = (lambda v: isinstance(v, list) and 0 < len(v) <= 64 and all(_is_num(x) for x in v),
         "a non-empty list of finite numbers")
_COUNT = (lambda v: _is_int(v) and v >= 0, "an integer >= 0")
_TEXT = (lambda v: isinstance(v, str) and bool(v.strip()) and len(v) <= 1000, "a non-empty string")
_NUM = (_is_num, "a finite number")
RECORD_FIELDS: dict[str, dict[str, tuple]] = {
    "header": {"format": (lambda v: isinstance(v, str), "a string"),
               "config": (lambda v: isinstance(v, dict), "a mapping (the study config)")},
    "episode": {"episode": _COUNT, "position": _TEXT, "taps": (lambda v: _is_int(v) and 0 <= v <= 64,
                                                               "an integer in 0..64")},
    "observe": {"episode": _COUNT, "u": _NUMS, "y": _NUMS},
    "decide": {"episode": _COUNT, "k": _COUNT, "action": _NUMS, "action_index": _COUNT,
               "predicted": (lambda v: _is_num(v) and v >= 0, "a finite number >= 0"),
               "retained_lo": _NUM, "retained_hi": _NUM, "hull_lo": _NUM, "hull_hi": _NUM},
    "outcome": {"episode": _COUNT},
    "truth": {"position": _TEXT, "theta": _NUMS},
    "rejected": {"call": _TEXT, "reason": (lambda v: isinstance(v, str), "a string")},
    "note": {"text": (lambda v: isinstance(v, str), "a string")},
}
#: Optional fields with a rule when present.
OPTIONAL_FIELDS: dict[str, dict[str, tuple]] = {
    "observe": {"j": (lambda v: _is_int(v) and v >= 1, "an integer >= 1"), "scheduled": _NUMS},
    "decide": {"n_retained": (lambda v: _is_int(v) and v >= 1, "an integer >= 1")},
    "outcome": {"entered": (lambda v: v is None or isinstance(v, bool), "true, false or null"),
                "notes": (lambda v: isinstance(v, dict), "a mapping")},
}


def check_record(record: Any, where: str) -> None:
    """The session-log rules of one record, on write and on read alike (no model needed).

    Raises:
        SessionLogError: ``<where>: <type> record: field 'f' must be ..., got ...``.
    """
    if not isinstance(record, dict) or record.get("type") not in RECORD_TYPES:
        raise SessionLogError(f"{where} is not a session record (needs 'type' in {', '.join(RECORD_TYPES)})")
    kind = record["type"]
    if kind == "header" and record.get("format") != LOG_FORMAT:
        raise SessionLogError(f"{where}: header format {record.get('format')!r:.80}, this version reads {LOG_FORMAT!r}")
    for name, (ok, what) in RECORD_FIELDS[kind].items():
        if name not in record:
            raise SessionLogError(f"{where}: {kind} record lacks field '{name}' ({what})")
        if not ok(record[name]):
            raise SessionLogError(f"{where}: {kind} record: field '{name}' must be {what}, got {record[name]!r:.80}")
    for name, (ok, what) in OPTIONAL_FIELDS.get(kind, {}).items():
        if name in record and not ok(record[name]):
            raise SessionLogError(f"{where}: {kind} record: field '{name}' must be {what}, got {record[name]!r:.80}")
    if kind == "decide":
        for lo, hi in (("retained_lo", "retained_hi"), ("hull_lo", "hull_hi")):
            if record[lo] > record[hi]:
                raise SessionLogError(f"{where}: decide record: {lo} {record[lo]!r} > {hi} {record[hi]!r}")


def read_records(path: str | Path, *, allow_partial: bool = False) -> tuple[list[dict[str, Any]], bytes]:
    """Every record of a log, checked by :func:`check_record`, and the bytes of a cut-off last line.

    JSON's non-standard ``NaN``/``Infinity`` are refused like any non-finite number.

    Raises:
        SessionLogError: a line that is not a valid record (naming it and its field), a
            missing or foreign header, or (unless ``allow_partial``) a cut-off last line.
    """
    path = log_path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SessionLogError(f"{path}: cannot read: {exc.strerror or exc}") from None
    partial = b""
    lines = raw.split(b"\n")
    if lines and lines[-1] != b"":
        partial = lines[-1]
    lines = lines[:-1]
    if partial and not allow_partial:
        raise SessionLogError(
            f"{path}: line {len(lines) + 1} was cut off mid-write ({len(partial)} bytes, no newline): the process "
            "stopped while writing it, so that call never returned. Reopen it with repair (Session.open(..., "
            f"repair=True); CLI: probecommit robot simulate --repair) to move it to {path.name}.partial and go on")
    records = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line, parse_constant=_no_constant)
        except UnicodeDecodeError:
            raise SessionLogError(f"{path}: line {number} is not UTF-8 text") from None
        except json.JSONDecodeError as exc:
            raise SessionLogError(f"{path}: line {number} is not valid JSON ({exc.msg} at column {exc.colno})") from None
        except (ValueError, RecursionError) as exc:
            raise SessionLogError(f"{path}: line {number}: {exc}") from None
        check_record(record, f"{path}: line {number}")
        record["_line"] = number
        records.append(record)
    if not records or records[0]["type"] != "header":
        raise SessionLogError(f"{path}: the first line must be the session header; this is not a probecommit session log")
    if records[0].get("format") != LOG_FORMAT:
        raise SessionLogError(f"{path}: header format {records[0].get('format')!r}, this version reads {LOG_FORMAT!r}")
    return records, partial


def _lock_fd(fd: int) -> bool:
    """Take an exclusive, non-blocking lock on an open file; False when another process holds it."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: lock the first byte of the file itself
        import msvcrt

        try:
            os.lseek(fd, 0, os.SEEK_SET)
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
            return True
        except OSError:
            return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)


def _open_no_symlink(path: Path, flags: int) -> int:
    """``os.open`` that refuses a symlink at ``path`` (a planted link is never followed)."""
    if path.is_symlink():
        raise SessionLogError(f"{path} is a symbolic link; refusing to follow it (remove it: a session "
                              "writes only files it created)")
    try:
        return os.open(path, flags | _NOFOLLOW | _CLOEXEC, 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SessionLogError(f"{path} is a symbolic link; refusing to follow it") from None
        raise


class SessionLog:
    """The writer of one session log (see the module docstring).

    The lock is an advisory lock on the log file itself (not on a side file that could be
    deleted to let a second writer in). ``<log>.lock`` only names the holder for the
    refusal message; a symlink planted there is refused, never written through.

    Args:
        path: The log file (``.jsonl``) or a directory holding ``session.jsonl``.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = log_path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd: int | None = None

    # ------------------------------------------------------------------ lock
    @property
    def _holder_path(self) -> Path:
        return self.path.with_name(self.path.name + ".lock")

    def acquire(self) -> None:
        """Take the writer's lock, or raise :class:`SessionLocked` naming the holder."""
        fd = _open_no_symlink(self.path, os.O_RDWR | os.O_CREAT | os.O_APPEND)
        if not _lock_fd(fd):
            os.close(fd)
            holder = "another process"
            try:
                if not self._holder_path.is_symlink():
                    holder = self._holder_path.read_text(errors="replace").strip() or holder
            except OSError:
                pass
            raise SessionLocked(f"{self.path} is open for writing by {holder}; one writer per log "
                                "(close that session, or wait for it to exit)")
        self._fd = fd
        try:
            note = _open_no_symlink(self._holder_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        except BaseException:
            self.release()
            raise
        try:
            os.write(note, f"pid {os.getpid()} on {socket.gethostname()} since "
                           f"{time.strftime('%Y-%m-%dT%H:%M:%S')}".encode())
        finally:
            os.close(note)

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases its lock
            self._fd = None

    # ------------------------------------------------------------------ writing
    def move_partial(self, partial: bytes) -> Path:
        """Move a cut-off last line to ``<log>.partial`` (appended, never overwritten) and truncate it."""
        side = self.path.with_name(self.path.name + ".partial")
        out = _open_no_symlink(side, os.O_WRONLY | os.O_CREAT | os.O_APPEND)
        try:
            _write_all(out, partial + b"\n", side)
            os.fsync(out)
        finally:
            os.close(out)
        size = os.fstat(self._fd).st_size
        os.ftruncate(self._fd, size - len(partial))
        os.fsync(self._fd)
        return side

    def append(self, record: dict[str, Any]) -> None:
        """Write one record as one line with one ``os.write``, then fsync, before returning.

        All or nothing: the record is checked first (:func:`check_record`); the bytes go to
        an unbuffered descriptor, so a failed write (disk full) leaves nothing behind to be
        flushed with a later record; a short write is truncated back and raised.

        Raises:
            SessionLogError: the record breaks the session-log rules.
            OSError: the write failed (the path is named); the log is as it was before.
        """
        if self._fd is None:
            raise RuntimeError("the session log is not open for writing")
        record = {k: v for k, v in record.items() if not k.startswith("_")}
        line = json.dumps(_finite(record), separators=(",", ":"), allow_nan=False) + "\n"
        check_record(json.loads(line), f"{self.path}: record to write")
        data = line.encode()
        before = os.fstat(self._fd).st_size
        try:
            _write_all(self._fd, data, self.path)
            os.fsync(self._fd)
        except BaseException:
            try:
                os.ftruncate(self._fd, before)
            except OSError:
                pass
            raise

    def __enter__(self) -> "SessionLog":
        self.acquire()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.release()


def _write_all(fd: int, data: bytes, path: Path) -> None:
    """One ``os.write`` of ``data``; a short write is an error naming ``path`` (the caller truncates back)."""
    try:
        written = os.write(fd, data)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    if written != len(data):
        raise OSError(errno.ENOSPC, f"short write ({written} of {len(data)} bytes)", str(path))


def iter_type(records: list[dict[str, Any]], kind: str) -> Iterator[dict[str, Any]]:
    return (r for r in records if r["type"] == kind)
