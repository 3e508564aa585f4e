"""The layer contract of docs/contributing.md holds (import-linter, configured in pyproject.toml).

Dependencies point one way: cli > report > studies > runner > audit > store > tasks >
engines > accel > core > process (process plumbing: memory estimates, the heap); core, audit, store and every task model import no engine, Ray or
plotting; the core maths imports no compiled layer (accel, numba). A planted violation must
be caught, so the check itself can fail.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def lint(cwd: Path, src: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name("lint-imports")
    env = {"PYTHONPATH": str(src), "PATH": str(exe.parent)}
    return subprocess.run([str(exe), "--no-cache"], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_layers_hold():
    result = lint(ROOT, ROOT / "src")
    assert result.returncode == 0, result.stdout[-3000:]
    assert "BROKEN" not in result.stdout


def _planted_copy(tmp_path: Path) -> Path:
    """A copy of the package's source under ``tmp_path / "src"`` to plant violations in."""
    copy = tmp_path / "src"
    shutil.copytree(ROOT / "src" / "probecommit", copy / "probecommit", ignore=shutil.ignore_patterns("__pycache__"))
    return copy


def _plant(copy: Path, module: str, line: str) -> None:
    """Append ``line`` to ``module`` (a path under probecommit/) of a planted copy."""
    path = copy / "probecommit" / module
    path.write_text(path.read_text() + f"\n{line}  # planted\n")


def planted(tmp_path: Path, module: str, line: str) -> subprocess.CompletedProcess:
    """The layer check on a copy of the package with ``line`` planted in ``module``."""
    copy = _planted_copy(tmp_path)
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    _plant(copy, module, line)
    return lint(tmp_path, copy)


def test_a_planted_upward_import_is_caught(tmp_path):
    result = planted(tmp_path, "core/retained.py", "from probecommit.runner import study")
    assert result.returncode != 0
    assert "probecommit.core is not allowed to import probecommit.runner" in result.stdout


def test_a_planted_import_of_the_compiled_layer_in_the_core_maths_is_caught(tmp_path):
    """The core maths (the NumPy reference) never reaches the accelerator-specific code."""
    result = planted(tmp_path, "core/belief.py", "from probecommit.accel import retained")
    assert result.returncode != 0
    assert "probecommit.core is not allowed to import probecommit.accel" in result.stdout


def test_a_planted_import_of_the_maths_in_the_process_plumbing_is_caught(tmp_path):
    """``process/`` (memory estimates, the heap) sits below the maths: every layer may use it, it uses none."""
    result = planted(tmp_path, "process/memory.py", "from probecommit.core import belief")
    assert result.returncode != 0
    assert "probecommit.process is not allowed to import probecommit.core" in result.stdout


# ---------------------------------------------------------------------------------- nothing generic names a family
#: Generic packages: they serve every family, so none may import a family's package or name one in a
#: string (the family supplies what they need through its spec and model: the default family, replay
#: shorthands, figure guides, observation range).
GENERIC = ("core", "accel", "process", "engines", "store", "audit", "runner", "robot", "cli")
#: Files of generic packages that drive the paper's own studies (reproduce, scan), which name their
#: families by design, like everything in studies/ and report/.
PAPER_DRIVERS = {"cli/study_commands.py"}
#: Modules of probecommit.tasks that are contract, not a family.
CONTRACT = {"base", "config", "registry", "declare", "adapters"}


def family_names(src: Path) -> set[str]:
    """The built-in families: every package folder under tasks/ (the registry discovers the same)."""
    tasks = src / "probecommit" / "tasks"
    return {p.name for p in tasks.iterdir() if (p / "__init__.py").is_file() and p.name not in CONTRACT}


def family_mentions(src: Path) -> list[str]:
    """``file:line: what`` for every import of a family package and every string equal to a family's name
    in generic code (docstrings and help text may mention a family in prose; an exact name may not)."""
    import ast

    names, found = family_names(src), []
    root = src / "probecommit"
    for package in GENERIC:
        for path in sorted((root / package).rglob("*.py")):
            rel = path.relative_to(root).as_posix()
            if rel in PAPER_DRIVERS:
                continue
            for node in ast.walk(ast.parse(path.read_text(), rel)):
                modules = []
                if isinstance(node, ast.ImportFrom) and node.module:
                    modules = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
                elif isinstance(node, ast.Import):
                    modules = [a.name for a in node.names]
                for module in modules:
                    parts = module.split(".")
                    if parts[:2] == ["probecommit", "tasks"] and len(parts) > 2 and parts[2] in names:
                        found.append(f"{rel}:{node.lineno}: imports {module}")
                        break
                if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                    found.append(f"{rel}:{node.lineno}: names the family {node.value!r}")
    return sorted(set(found))


def test_nothing_generic_names_a_family():
    assert family_mentions(ROOT / "src") == []


@pytest.mark.parametrize("target,line", [
    ("runner/study.py", "from probecommit.tasks.insertion.model import InsertionModel"),
    ("audit/metrics.py", "import probecommit.tasks.push1d"),
    ("store/schema.py", "from probecommit.tasks import rig"),
    ("robot/session.py", "from probecommit.tasks.rig.model import rig_half_gap"),
    ("cli/app.py", "from probecommit.tasks.insertion import make_simulator"),
    ("runner/config.py", 'DEFAULT_FAMILY = "insertion"'),
    ("cli/robot_commands.py", 'IS_RIG = lambda c: c.family == "rig"'),
])
def test_a_planted_family_mention_is_caught(tmp_path, target, line):
    copy = _planted_copy(tmp_path)
    _plant(copy, target, line)
    found = family_mentions(copy)
    assert len(found) == 1 and found[0].startswith(f"{target}:"), found


# ---------------------------------------------------------------------------------- no import circle in the CLI
def cli_import_cycles(src: Path) -> list[list[str]]:
    """Cycles among ``probecommit.cli`` modules, counting every import (function-level ones too)."""
    import ast

    root = src / "probecommit" / "cli"
    names = {p.stem for p in root.glob("*.py")}
    graph: dict[str, set[str]] = {}
    for path in root.glob("*.py"):
        edges = graph.setdefault(path.stem, set())
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                parts = node.module.split(".")
                if parts[:2] == ["probecommit", "cli"]:
                    targets = [parts[2]] if len(parts) > 2 else [a.name for a in node.names]
                    edges.update(t for t in targets if t in names and t != path.stem)
    cycles, state = [], {}

    def visit(node: str, stack: list[str]) -> None:
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    return cycles


def test_the_cli_has_no_import_circle(tmp_path):
    assert cli_import_cycles(ROOT / "src") == []
    copy = _planted_copy(tmp_path)  # and a planted circle is caught
    _plant(copy, "cli/output.py", "from probecommit.cli.audit_commands import audit_command")
    assert cli_import_cycles(copy) == [["audit_commands", "output", "audit_commands"]]
