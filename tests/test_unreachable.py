"""No statement follows a ``return``, ``raise``, ``continue`` or ``break`` in its block: such code never runs
and reads as if it did (a refactor once left a whole old function body after its new ``return``)."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "probecommit"


def unreachable(path: Path, root: Path = SRC) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        for field in ("body", "orelse", "finalbody", "handlers"):
            block = getattr(node, field, None)
            if not isinstance(block, list):
                continue
            for stmt, after in zip(block, block[1:]):
                if isinstance(stmt, (ast.Return, ast.Raise, ast.Continue, ast.Break)):
                    found.append(f"{path.relative_to(root)}:{after.lineno}")
    return found


def test_no_code_after_a_return_raise_continue_or_break():
    found = [where for path in sorted(SRC.rglob("*.py")) for where in unreachable(path)]
    assert not found, found


def test_the_check_finds_code_after_a_return(tmp_path):
    bad = tmp_path / "probe.py"
    bad.write_text("def f():\n    return 1\n    x = 2\n")
    assert unreachable(bad, tmp_path) == ["probe.py:3"]
