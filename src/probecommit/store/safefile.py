"""The one way a user-visible file is written: never through a symlink the writer did not create.

A run directory, a session folder or an output folder may hold a link planted by someone
else (``audit.csv -> ~/.bashrc``). Writing with ``open(path, "w")`` follows it and
clobbers the target. Every writer therefore goes through :func:`write_bytes`: it refuses
a symlink at the destination, writes a fresh temporary file beside it (created with
``O_EXCL``, so it cannot be a link either), fsyncs it and renames it over the
destination (a rename replaces a name, it never follows one). A reader never sees half
a file. Frames, figures and text are rendered to bytes in memory first.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path
from typing import Any, BinaryIO, Callable, Iterator


def _read_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: Read once at import: reading the umask means setting it, which is process-global.
_UMASK = _read_umask()


class UnsafePathError(OSError):
    """The destination is a symlink (or a symlinked output folder); nothing was written."""


def refuse_symlink(path: str | Path, what: str = "file") -> Path:
    """``path``, after checking that it is not a symbolic link.

    Raises:
        UnsafePathError: naming the path and where the link points.
    """
    path = Path(path)
    if path.is_symlink():
        target = os.readlink(path)
        raise UnsafePathError(f"{path} is a symbolic link (to {target}); refusing to write the {what} through "
                              "it (remove the link, or choose another output folder)")
    return path


def output_dir(chosen: str | Path | None, default: str | Path) -> Path:
    """An output folder, created if missing: the user's ``chosen`` one as it is (a link they made is
    theirs), else ``default``, which is refused if it is a symlink (a folder inside a run directory
    pointing elsewhere would put the files outside the run)."""
    path = Path(chosen) if chosen is not None else refuse_symlink(default, "output folder")
    path.mkdir(parents=True, exist_ok=True)
    return path


@contextlib.contextmanager
def atomic_file(path: Path) -> Iterator[BinaryIO]:
    """A file to write whose content replaces ``path`` atomically when the block ends (a
    temporary file beside it, fsync, rename); nothing is left behind when it raises. The file
    gets the mode any new file would (the umask's), not mkstemp's 0600."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)
        with os.fdopen(fd, "wb") as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        refuse_symlink(path)  # planted between a caller's check and now: not followed by the rename, and said
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path``: refuse a symlink there, write a temporary file, fsync, rename.

    Raises:
        UnsafePathError: ``path`` is a symlink.
        OSError: the write failed (the message names ``path``); nothing is left behind.
    """
    path = refuse_symlink(path)
    try:
        with atomic_file(path) as fh:
            fh.write(data)
    except OSError as exc:
        if isinstance(exc, UnsafePathError) or exc.filename:
            raise
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    return path


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """:func:`write_bytes` of ``text`` encoded."""
    return write_bytes(path, text.encode(encoding))


def write_with(path: str | Path, render: Callable[[io.BytesIO], Any]) -> Path:
    """:func:`write_bytes` of what ``render`` writes into a buffer (``frame.to_parquet``, ``fig.savefig``)."""
    buffer = io.BytesIO()
    render(buffer)
    return write_bytes(path, buffer.getvalue())
