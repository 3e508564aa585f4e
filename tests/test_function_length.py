"""No function of the package is longer than a screen (issue 43: functions that fit a screen).

A long function is split into named steps whose docstrings say why; the checker counts a
function's lines from its ``def`` to its last line (docstring and comments included), nested
functions within their parent. An exception is listed below with its reason, and the list is
checked both ways: an entry that is no longer needed fails too, so it cannot go stale.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "probecommit"
#: Most lines a function may take.
MAX_LINES = 80
#: ``"path/relative/to/probecommit.py:function"`` -> why it stays longer. Keep it short.
ALLOWED: dict[str, str] = {}


def long_functions(root: Path = SRC, limit: int = MAX_LINES) -> dict[str, int]:
    """``"file:function"`` -> lines, for every function (methods and nested ones included) over ``limit``."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[f"{path.relative_to(root).as_posix()}:{node.name}"] = lines
    return found


def test_no_function_is_longer_than_a_screen():
    long = long_functions()
    unexplained = {name: n for name, n in long.items() if name not in ALLOWED}
    assert not unexplained, f"functions over {MAX_LINES} lines (split them into named steps): {unexplained}"
    stale = sorted(set(ALLOWED) - set(long))
    assert not stale, f"allowed exceptions no longer over {MAX_LINES} lines (remove them): {stale}"


def test_the_checker_finds_a_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES))
    (tmp_path / "m.py").write_text(f"def short():\n    return 1\n\n\ndef long():\n{body}\n    return 0\n")
    assert long_functions(tmp_path) == {"m.py:long": MAX_LINES + 2}
