"""Hash manifests of a publication, and the binding of each figure to the data it was drawn from.

Why: a manifest says which files a publication holds and their bytes; it proves nothing about
whether a number follows from the data (that is ``report.recompute``'s job), but it makes a
deleted, added or renamed file an error, and it ties each figure to the digest of its data.

Two kinds of manifest, both ``MANIFEST.json``:

* a **study manifest** (``results/paper/<study>/MANIFEST.json``): ``{"sha256": {name: digest},
  "figures": {figure: {"data": [names], "data_sha256": digest}}}``; every file of the folder
  must be listed;
* the **publication manifest** (``results/paper/MANIFEST.json``): the files at the root
  (``reproduction.json``, ``report.html``, the ledger) and REPRODUCTION.md, named relative to
  the root (``../../REPRODUCTION.md``), and the list of study folders.

A figure's PNG also carries its data digest in a ``tEXt`` chunk (key ``probecommit-data``), so
a figure copied from another study names another study's data and fails.
"""

from __future__ import annotations

import hashlib
import json
import struct
import zlib
from pathlib import Path
from typing import Any
from probecommit.store.manifest_rules import sha256_file
from probecommit.store.safefile import write_bytes, write_text

MANIFEST = "MANIFEST.json"
REPRODUCTION_MD = "REPRODUCTION.md"
#: REPRODUCTION.md relative to the publication root (``results/paper`` in a checkout).
REPRODUCTION_REL = "../../REPRODUCTION.md"
PNG_KEY = b"probecommit-data"

#: Figure -> the stored tables it is drawn from (per study). A figure not listed is drawn from
#: run directories the publication does not hold; verify reports it as bound to no data.
FIGURE_DATA: dict[str, dict[str, tuple[str, ...]]] = {
    "insertion": {"fig_7_signatures": ("fault_signatures.parquet",),
                  "fig_6_decision": ("coverage_vs_nominal.parquet", "gates_curves.parquet"),
                  "fig_4a_teaser_scan_section": ("scan.parquet", "scan_grid.parquet"),
                  "fig_4b_teaser_decisive_tap": ("decisive_tap.parquet",)},
    "breadth": {"fig_breadth_budget": ("budget_curves.parquet",)},
    "cost": {"fig_pricing": ("pricing.parquet",)},
    "robot": {"fig_5b_hardware_simulated_rig_aim_error": ("robot_episodes.parquet",),
              "fig_5c_hardware_simulated_rig_boundary_fault": ("fault_boundary.parquet",),
              "fig_5d_hardware_simulated_rig_prior_fault": ("fault_prior.parquet",)},
    "setup": {"fig_1b_overview_belief": ("fig_1b_data.parquet",)},
    "engines": {}, "beyond": {}, "gru": {}, "figures": {},
}
#: Figures drawn from code alone (no data): verify draws them again and compares the bytes.
CODE_FIGURES: dict[str, tuple[str, ...]] = {"figures": ("fig_2_pipeline",)}


def data_digest(folder: Path, names: tuple[str, ...] | list[str]) -> str:
    """One digest of several data files (name and bytes of each, in order)."""
    digest = hashlib.sha256()
    for name in names:
        digest.update(name.encode() + b"\0" + bytes.fromhex(sha256_file(folder / name)))
    return digest.hexdigest()


# ----------------------------------------------------------------------------- PNG text chunk


def _chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    out, at = [], 8
    while at < len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        kind = data[at + 4:at + 8]
        out.append((kind, data[at + 8:at + 8 + length]))
        at += 12 + length
    return out


def png_data_digest(path: Path) -> str | None:
    """The data digest a PNG carries (``probecommit-data`` text chunk), or None."""
    for kind, body in _chunks(path.read_bytes()):
        if kind == b"tEXt" and body.startswith(PNG_KEY + b"\0"):
            return body[len(PNG_KEY) + 1:].decode("ascii")
    return None


def strip_stamp(data: bytes) -> bytes:
    """A PNG's bytes without the data-digest chunk (how the figure was drawn, before publishing)."""
    out = bytearray(data[:8])
    for kind, payload in _chunks(data):
        if not (kind == b"tEXt" and payload.startswith(PNG_KEY + b"\0")):
            out += struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))
    return bytes(out)


def stamp_png(path: Path, digest: str) -> None:
    """Write ``digest`` into the PNG's text chunk (replacing an earlier one), pixels untouched."""
    data = path.read_bytes()
    chunks = [(k, b) for k, b in _chunks(data) if not (k == b"tEXt" and b.startswith(PNG_KEY + b"\0"))]
    body = PNG_KEY + b"\0" + digest.encode("ascii")
    chunks.insert(len(chunks) - 1, (b"tEXt", body))  # before IEND
    out = bytearray(data[:8])
    for kind, payload in chunks:
        out += struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))
    write_bytes(path, bytes(out))


# ----------------------------------------------------------------------------- writing


def figure_bindings(study_dir: Path) -> dict[str, dict[str, Any]]:
    """Each figure of a study folder with its data files and their digest (unbound: empty data)."""
    declared = FIGURE_DATA.get(study_dir.name, {})
    out: dict[str, dict[str, Any]] = {}
    for png in sorted(study_dir.glob("*.png")):
        names = [n for n in declared.get(png.stem, ()) if (study_dir / n).is_file()]
        out[png.name] = {"data": names, "data_sha256": data_digest(study_dir, names) if names else None}
    return out


def study_files(study_dir: Path) -> list[str]:
    """The files a study manifest lists: every file of the folder but the manifest itself, by name
    (one list for writing the manifest and for ``verify``'s check that it lists them all)."""
    return sorted(p.name for p in study_dir.iterdir() if p.is_file() and p.name != MANIFEST)


def write_manifest(study_dir: str | Path) -> Path:
    """Stamp each figure with its data digest, then hash every file of the study folder."""
    study_dir = Path(study_dir)
    figures = figure_bindings(study_dir)
    for name, binding in figures.items():
        if binding["data_sha256"]:
            stamp_png(study_dir / name, binding["data_sha256"])
    manifest = {"sha256": {name: sha256_file(study_dir / name) for name in study_files(study_dir)}, "figures": figures}
    path = study_dir / MANIFEST
    write_text(path, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return path


def root_files(root: Path) -> list[str]:
    """The publication root's own files (relative names), REPRODUCTION.md included when present."""
    names = sorted(p.name for p in root.iterdir() if p.is_file() and p.name != MANIFEST)
    if (root / REPRODUCTION_REL).is_file():
        names.append(REPRODUCTION_REL)
    return names


def write_root_manifest(root: str | Path) -> Path:
    """The publication manifest: root files, REPRODUCTION.md and the study folders."""
    root = Path(root)
    studies = sorted(p.name for p in root.iterdir() if p.is_dir())
    manifest = {"sha256": {n: sha256_file(root / n) for n in root_files(root)}, "studies": studies}
    path = root / MANIFEST
    write_text(path, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return path


def write_all(root: str | Path) -> None:
    """Re-hash every study folder and then the publication root (publishing's last step)."""
    root = Path(root)
    for study in sorted(p for p in root.iterdir() if p.is_dir()):
        write_manifest(study)
    write_root_manifest(root)
