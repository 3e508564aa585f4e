"""Group-committed shard batches: many finished units in one durable file.

A run's units are written to ``shards/batch-NNNNNN.pcb`` a batch at a time: one temporary
file, one fsync, one rename, one fsync of the directory, however many units the batch
holds (a file per table per unit cost five fsyncs a unit and dominated short runs). A
batch is whole or absent (atomic rename), so resuming works at batch granularity: the
units of every readable batch are done, the rest run again.

Every batch records the code identity (:func:`probecommit.store.rundir.code_identity`,
the same sha256 the manifest records) and the version that wrote it, so a run directory
can prove it never holds results of two builds.

File layout::

    b"PCBATCH1\\n" | header length (8 bytes, little-endian) | header (JSON) | payload

The header names the code, the version, the sha256 of the payload and, per unit, its
stats and the ``[offset, length]`` of each table in the payload. Tables are Arrow IPC
streams: read back they equal the tables written (schema and pandas metadata included),
with no Parquet encoding per unit.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import pyarrow as pa

MAGIC = b"PCBATCH1\n"
SUFFIX = ".pcb"
PREFIX = "batch-"
#: The tables every unit stores, in payload order.
UNIT_TABLES = ("instances", "probes", "engine_cache", "episodes")


class BatchError(ValueError):
    """A batch file is not one (cut short, altered or of another format)."""


def batch_name(index: int) -> str:
    return f"{PREFIX}{index:06d}{SUFFIX}"


def batch_index(path: Path) -> int | None:
    """The number in a batch file's name; None for any other name."""
    name = path.name
    if not (name.startswith(PREFIX) and name.endswith(SUFFIX)):
        return None
    digits = name[len(PREFIX):-len(SUFFIX)]
    return int(digits) if digits.isdigit() else None


def _ipc_bytes(table: pa.Table) -> bytes:
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write_table(table)
    return sink.getvalue().to_pybytes()


def encode(units: list[tuple[str, dict[str, pa.Table], dict[str, Any]]], code: str, version: str) -> bytes:
    """The bytes of a batch holding ``units`` (name, Arrow tables by :data:`UNIT_TABLES`, stats)."""
    blobs: list[bytes] = []
    entries = []
    offset = 0
    for unit, tables, stats in units:
        spans = {}
        for name in UNIT_TABLES:
            data = _ipc_bytes(tables[name])
            spans[name] = [offset, len(data)]
            blobs.append(data)
            offset += len(data)
        entries.append({"unit": unit, "stats": stats, "tables": spans})
    payload = b"".join(blobs)
    header = json.dumps({"code": code, "version": version, "payload_bytes": len(payload),
                         "payload_sha256": hashlib.sha256(payload).hexdigest(), "units": entries}).encode()
    return MAGIC + len(header).to_bytes(8, "little") + header + payload


def _split(data: bytes, name: str) -> tuple[dict[str, Any], memoryview]:
    if not data.startswith(MAGIC) or len(data) < len(MAGIC) + 8:
        raise BatchError(f"{name} is not a probecommit batch file")
    start = len(MAGIC) + 8
    size = int.from_bytes(data[len(MAGIC):start], "little")
    try:
        header = json.loads(data[start:start + size])
    except ValueError:
        raise BatchError(f"{name} has an unreadable header") from None
    if not isinstance(header, dict) or not isinstance(header.get("units"), list):
        raise BatchError(f"{name} has a malformed header")
    return header, memoryview(data)[start + size:]


def read_header(path: Path) -> dict[str, Any]:
    """A batch's header, read without its payload (whose length is checked against it).

    Raises:
        BatchError: the file is not a whole batch.
    """
    with open(path, "rb") as fh:
        head = fh.read(len(MAGIC) + 8)
        if not head.startswith(MAGIC) or len(head) < len(MAGIC) + 8:
            raise BatchError(f"{path.name} is not a probecommit batch file")
        size = int.from_bytes(head[len(MAGIC):], "little")
        header, _ = _split(head + fh.read(size), path.name)
        rest = fh.seek(0, 2) - len(head) - size
    if rest != header.get("payload_bytes"):
        raise BatchError(f"{path.name} is cut short or has bytes appended")
    return header


def read(path: Path) -> tuple[dict[str, Any], dict[str, dict[str, pa.Table]]]:
    """A batch's header and each unit's tables, the payload checked against its sha256.

    Raises:
        BatchError: the file is not a whole, unaltered batch.
    """
    header, payload = _split(path.read_bytes(), path.name)
    if hashlib.sha256(payload).hexdigest() != header.get("payload_sha256"):
        raise BatchError(f"{path.name} changed since it was written (payload sha256 differs)")
    buffer = pa.py_buffer(payload)
    units = {}
    for entry in header["units"]:
        units[entry["unit"]] = {name: pa.ipc.open_stream(buffer.slice(off, length)).read_all()
                                for name, (off, length) in entry["tables"].items()}
    return header, units
