"""The ledger's declared literals and its coverage check: a number typed into prose fails."""

from __future__ import annotations

import json

from probecommit.report import ledger


def _publication(tmp_path, text: str, build) -> list[ledger.Entry]:
    (tmp_path / "insertion").mkdir()
    (tmp_path / "insertion" / "results.json").write_text(json.dumps({"results": {"escape": 0.1234, "n": 96}}))
    book = ledger.Ledger()
    build(book)
    (tmp_path / "R.md").write_text(text)
    book.write(tmp_path)
    return ledger.read(tmp_path)


def _build(book: ledger.Ledger) -> None:
    n = book.for_file("R.md")
    book.literal("R.md", "Table 5", "the paper's table number")
    n("insertion:results.escape", 0.1234)
    n("insertion:results.n", 96, "d")


def test_a_fully_declared_file_passes(tmp_path):
    entries = _publication(tmp_path, "## Table 5\n\nescape 0.123 over 96 truths\n", _build)
    assert list(ledger.check(entries, tmp_path)) == []
    assert list(ledger.uncovered(entries, tmp_path)) == []


def test_a_number_typed_into_prose_is_uncovered(tmp_path):
    entries = _publication(tmp_path, "## Table 5\n\nescape 0.123 over 96 truths (paper: 0.169)\n", _build)
    assert list(ledger.uncovered(entries, tmp_path)) == [
        "R.md: prints 0.169 at line 3, which no ledger entry or declared literal accounts for"]


def test_a_literal_moved_or_changed_is_caught(tmp_path):
    entries = _publication(tmp_path, "## Table 6\n\nescape 0.123 over 96 truths\n", _build)
    problems = list(ledger.check(entries, tmp_path))
    assert any("declared literal 'Table 5'" in p for p in problems)
    assert any("prints 6 at line 1" in p for p in ledger.uncovered(entries, tmp_path))


def test_an_ours_number_changed_to_another_value_is_caught(tmp_path):
    entries = _publication(tmp_path, "## Table 5\n\nescape 0.169 over 96 truths\n", _build)
    assert any("does not contain 0.123" in p for p in ledger.check(entries, tmp_path))
    assert any("prints 0.169" in p for p in ledger.uncovered(entries, tmp_path))
