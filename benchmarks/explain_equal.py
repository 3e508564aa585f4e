"""Check: two explain results folders hold the same numbers (issue 42: a speed change moves none).

Usage::

    python benchmarks/explain_equal.py BEFORE/explain/results AFTER/explain/results

``results.json`` is compared key by key (every leaf, exact), every other file byte for byte; a
Parquet file whose bytes differ is read back and compared cell by cell (dtypes included), so the
line says whether only its encoding or its rows moved. Exit status 0 when everything is identical.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from probecommit.store.rundir import flatten_dotted


def parquet_cells(a: Path, b: Path) -> str:
    import pandas as pd

    try:
        pd.testing.assert_frame_equal(pd.read_parquet(a), pd.read_parquet(b), check_exact=True)
        return "cells equal, bytes differ"
    except AssertionError as error:
        return "cells differ: " + str(error).splitlines()[0][:200]


def compare(a: Path, b: Path) -> list[str]:
    """One line per difference (none: identical)."""
    out = []
    ja, jb = (flatten_dotted(json.loads((p / "results.json").read_text())) for p in (a, b))
    for key in sorted(set(ja) | set(jb)):
        if ja.get(key, "<absent>") != jb.get(key, "<absent>"):
            out.append(f"results.json {key}: {ja.get(key, '<absent>')!r} -> {jb.get(key, '<absent>')!r}")
    fa = {p.relative_to(a) for p in a.rglob("*") if p.is_file()}
    fb = {p.relative_to(b) for p in b.rglob("*") if p.is_file()}
    out += [f"only in {a}: {p}" for p in sorted(fa - fb)] + [f"only in {b}: {p}" for p in sorted(fb - fa)]
    for rel in sorted(fa & fb):
        if (a / rel).read_bytes() != (b / rel).read_bytes():
            out.append(f"{rel}: " + (parquet_cells(a / rel, b / rel) if rel.suffix == ".parquet" else "bytes differ"))
    print(f"{len(ja)} results.json keys, {len(fa & fb)} files compared")
    return out


if __name__ == "__main__":
    differences = compare(Path(sys.argv[1]), Path(sys.argv[2]))
    print("\n".join(differences) or "identical: every key and every file")
    sys.exit(1 if differences else 0)
