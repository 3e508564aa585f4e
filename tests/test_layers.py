"""The layer contract of docs/contributing.md holds (import-linter, configured in pyproject.toml).

Dependencies point one way: cli > report > studies > runner > audit > store > tasks >
engines > core; core, audit, store and every task model import no engine, Ray or
plotting. A planted violation must be caught, so the check itself can fail.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def lint(cwd: Path, src: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("lint-imports")
    env = {"PYTHONPATH": str(src), "PATH": str(exe.parent)}
    return subprocess.run([str(exe), "--no-cache"], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_layers_hold():
    result = lint(ROOT, ROOT / "src")
    assert result.returncode == 0, result.stdout[-3000:]
    assert "BROKEN" not in result.stdout


def test_a_planted_upward_import_is_caught(tmp_path):
    copy = tmp_path / "src"
    shutil.copytree(ROOT / "src" / "probecommit", copy / "probecommit", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    model = copy / "probecommit" / "core" / "retained.py"
    model.write_text(model.read_text() + "\nfrom probecommit.runner import study  # planted\n")
    result = lint(tmp_path, copy)
    assert result.returncode != 0
    assert "probecommit.core is not allowed to import probecommit.runner" in result.stdout
