"""The manifest rule set: one reader for every ``manifest.json`` (run directories, result folders).

A manifest maps each file a reader relies on to its sha256. Integrity on read means the
manifest itself is well formed (a JSON object whose ``sha256`` is a non-empty mapping of
file name to 64 hex digits), every file the reader is about to read is listed in it,
and each listed file's digest matches. Every violation is one line naming the manifest
and the file or field; none is a traceback. The rules are documented in
``docs/record-schema.md`` (section "Manifests").
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Any, Iterable

from probecommit.errors import UserError

_HEX64 = re.compile(r"^[0-9a-f]{64}$")


class ManifestError(UserError, ValueError):
    """A manifest that is malformed, incomplete, or disagrees with the files; the message names them."""


def sha256_file(path: Path) -> str:
    """The sha256 of a file, read in 1 MiB blocks (a table is never held whole for its digest)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_json(path: str | Path, what: str = "JSON file") -> Any:
    """A JSON file's content; an unreadable or invalid file is one error naming it (JSON's
    non-standard NaN/Infinity are read, as Python writes them; callers check values).

    Raises:
        ManifestError: naming the file, the line and column.
    """
    path = Path(path)
    try:
        return json.loads(path.read_bytes().decode("utf-8"))
    except OSError as exc:
        raise ManifestError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ManifestError(f"{path}: not UTF-8 text; a {what} is JSON") from None
    except json.JSONDecodeError as exc:
        raise ManifestError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    except RecursionError:
        raise ManifestError(f"{path}: the JSON nests too deeply to read") from None


def read_manifest(path: str | Path) -> dict[str, Any]:
    """A manifest's content after the structural rules (see the module docstring).

    Raises:
        ManifestError: missing, unreadable, not JSON, not an object, or a ``sha256``
            entry that is not a non-empty mapping of relative file name to a hex digest.
    """
    path = Path(path)
    if not path.is_file():
        raise ManifestError(f"{path}: no such manifest")
    data = read_json(path, "manifest")
    if not isinstance(data, dict):
        raise ManifestError(f"{path}: a manifest must be a JSON object, got a JSON {type(data).__name__}")
    digests = data.get("sha256")
    if not isinstance(digests, dict) or not digests:
        shown = ("missing" if "sha256" not in data else "null" if digests is None else
                 "empty" if isinstance(digests, dict) else f"a JSON {type(digests).__name__}")
        raise ManifestError(f"{path}: field 'sha256' must map each file to its digest; it is {shown}")
    for name, value in digests.items():
        if not isinstance(value, str) or not _HEX64.match(value):
            raise ManifestError(f"{path}: sha256 of {name!r} must be 64 hex digits, got {value!r}")
        if Path(name).is_absolute() or ".." in Path(name).parts:
            raise ManifestError(f"{path}: file name {name!r} must be relative to the manifest's folder")
    return data


def verify_files(path: str | Path, required: Iterable[str]) -> dict[str, Any]:
    """Read a manifest and check that every ``required`` file is listed and every listed file matches.

    Raises:
        ManifestError: naming the first file that is unlisted, missing or changed.
    """
    path = Path(path)
    data = read_manifest(path)
    digests = data["sha256"]
    for name in required:
        if name not in digests:
            raise ManifestError(f"{path}: {name} is read but not listed in the manifest; refusing to trust it")
    for name, digest in digests.items():
        file = path.parent / name
        if not file.is_file():
            raise ManifestError(f"{file}: listed in {path.name} but missing")
        if sha256_file(file) != digest:
            raise ManifestError(f"{file} changed since {path.name} was written (sha256 differs); refusing an "
                                "altered file")
    return data
