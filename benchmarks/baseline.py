"""A git ref checked out beside this tree, for the benchmarks that measure against it (``--against REF``)."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path
from typing import Iterator

ROOT = Path(__file__).resolve().parents[1]


@contextlib.contextmanager
def baseline_tree(ref: str, where: Path) -> Iterator[Path]:
    """Check ``ref`` out into the worktree ``where`` with its compiled kernels built; removed on exit.

    The kernels are built files, not in git: without them the baseline would run numba's JIT
    (slower, and ~115-150 MB more resident). A ref that predates them fails that step quietly
    and runs as it did then.

    Yields:
        The worktree's root (its package is under ``src/``).
    """
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), ref], check=True,
                   capture_output=True)
    try:
        for build in ("probecommit.accel.compiled", "probecommit.core.compiled"):  # where the build is, by age
            subprocess.run([sys.executable, "-m", build], capture_output=True,
                           env={**os.environ, "PYTHONPATH": str(where / "src")})
        yield where
    finally:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(where)], capture_output=True)
