"""`probecommit verify` passes on the frozen results and catches planted errors."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.report.verify import verify, write_manifest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def results(tmp_path) -> Path:
    shutil.copytree(ROOT / "results", tmp_path / "results")
    shutil.copy(ROOT / "REPRODUCTION.md", tmp_path / "REPRODUCTION.md")
    return tmp_path / "results"


def test_frozen_results_pass_with_more_invariants_than_the_paper(results):
    report = verify(results)
    assert report.ok, report.failures[:5]
    assert report.checked > 788
    assert any("table_insertion.A.no_probe" in t for t in report.traces)


def _edit_json(results: Path, edit) -> None:
    path = results / "paper" / "insertion" / "results.json"
    payload = json.loads(path.read_text())
    edit(payload["results"])
    path.write_text(json.dumps(payload))


def test_a_changed_number_is_caught_even_with_a_fresh_manifest(results):
    # Point estimate moved outside its own interval; re-hashing does not hide it.
    _edit_json(results, lambda r: r["table_insertion"]["A.cover_k5"].__setitem__(0, 0.99))
    write_manifest(results / "paper" / "insertion")
    failures = verify(results).failures
    assert any("A.cover_k5 = 0.99 lies outside its interval" in f for f in failures)
    assert any("REPRODUCTION.md" in f and "A, cover k=5" in f for f in failures)


def test_a_broken_identity_is_caught(results):
    _edit_json(results, lambda r: r["table_testc"]["failure_random_k8"]["old_minus_corrected"].__setitem__(0, 0.2))
    write_manifest(results / "paper" / "insertion")
    assert any("old_minus_corrected" in f and "but old - corrected" in f for f in verify(results).failures)


def test_hash_mismatch_and_missing_file_are_caught(results):
    (results / "paper" / "insertion" / "scan.md").write_text("edited\n")
    (results / "paper" / "insertion" / "gates.md").unlink()
    failures = verify(results).failures
    assert any("scan.md: sha256 differs" in f for f in failures)
    assert any("gates.md: listed in MANIFEST.json but missing" in f for f in failures)


def test_cli_exit_codes(results):
    ok = CliRunner().invoke(app, ["verify", str(results)])
    assert ok.exit_code == 0 and "invariants checked, 0 failed" in ok.output
    (results / "paper" / "insertion" / "scan.parquet").write_bytes(b"not parquet")
    bad = CliRunner().invoke(app, ["verify", str(results)])
    assert bad.exit_code == 1


def test_a_robot_table_that_miscounts_its_window_is_caught(results):
    path = results / "paper" / "robot" / "results.json"
    payload = json.loads(path.read_text())
    payload["results"]["table"][0]["in_window"] += 1
    path.write_text(json.dumps(payload))
    write_manifest(results / "paper" / "robot")
    assert any("1 - in_window / episodes" in f for f in verify(results).failures)
