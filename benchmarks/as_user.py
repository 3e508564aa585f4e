"""The environment a benchmark runs ``probecommit`` in as a process: what a user's install has.

A user's install (``pip install``) compiles the package's bytecode once; a process then loads
``.pyc`` files. A shell with ``PYTHONDONTWRITEBYTECODE`` set (this project's agents and some CI
images) compiles every module from source in every process instead: about 0.15 s of CPU a
start-up here, which the user never pays. So the timed processes run without that variable,
on a tree whose bytecode :func:`compile_tree` wrote first (as ``pip`` would).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path


def user_env(src: Path, **extra: str) -> dict[str, str]:
    """This process's environment with ``PYTHONPATH=src``, bytecode caching allowed, plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return {**env, "PYTHONPATH": str(src), **extra}


def compile_tree(src: Path) -> None:
    """Write the bytecode of the package under ``src`` (``python -m compileall``, as an install does)."""
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(src / "probecommit")], check=True,
                   env=user_env(src), stdout=subprocess.DEVNULL)


def children_cpu() -> float:
    """User + system CPU seconds of the children waited for so far (their own children included)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime
