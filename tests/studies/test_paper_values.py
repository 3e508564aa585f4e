"""The paper-values table (``studies/paper_values.py``) against the seed text (the paper).

Every value REPRODUCTION.md prints in a "paper" column comes from that one table; this test
checks that each of its numbers is printed in the paper, so a mistyped or edited paper value
fails here (and a planted one shows that the check can fail).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Iterator

import pytest

from probecommit.studies.paper_values import PAPER as LEGACY
from probecommit.studies.paper_values import tree

#: The paper-values table as numbers (``tree()``), and the earlier float keys kept for old code.
PAPER = {**LEGACY, **tree()}

SEED = Path(__file__).resolve().parents[2].parent / "shared" / "seed" / "000_9d0aab961ea060bd.txt"
SEED_CANDIDATES = [SEED, Path("/work/shared/seed/000_9d0aab961ea060bd.txt")]


def _seed_text() -> str:
    for path in SEED_CANDIDATES:
        if path.is_file():
            return path.read_text()
    pytest.skip("the seed text (the paper) is not beside this checkout")


def _numbers(value: Any) -> Iterator[float]:
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        yield float(value)
    elif isinstance(value, dict):
        for v in value.values():
            yield from _numbers(v)
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _numbers(v)


def _printed(text: str) -> set[float]:
    """Every number the text prints (a Unicode minus read as a minus; ".82" read as 0.82; "89\\%" also as 0.89)."""
    text = text.replace("\u2212", "-").replace("\u2013", "-")
    out = set()
    for token, percent in re.findall(r"(?<![\d.])(-?(?:\d+\.\d+|\.\d+|\d+))(?![\d.]*[A-Za-z])(\\?%)?", text):
        out.add(float(token))
        if percent:
            out.add(float(token) / 100)
    return out


def _found(value: float, printed: set[float]) -> bool:
    return any(abs(value - p) < 1e-9 or abs(abs(value) - p) < 1e-9 for p in printed)


def _missing(paper: dict[str, Any], printed: set[float]) -> list[tuple[str, float]]:
    return [(key, v) for key, value in paper.items() for v in _numbers(value) if not _found(v, printed)]


def test_every_paper_value_is_printed_in_the_paper():
    missing = _missing(PAPER, _printed(_seed_text()))
    assert not missing, f"paper values not in the paper: {missing}"


def test_a_mistyped_paper_value_is_caught():
    printed = _printed(_seed_text())
    planted = dict(PAPER, **{"table_insertion.A.no_probe": 0.821, "table_faults.fail": {"none": 0.10, "noise": 0.1137}})
    assert _missing(planted, printed) == [("table_insertion.A.no_probe", 0.821), ("table_faults.fail", 0.1137)]
