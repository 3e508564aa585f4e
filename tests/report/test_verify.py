"""`probecommit verify`: the frozen publication and a scratch one pass; the CLI reports by kind."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.report.verify import publication_root, verify

ROOT = Path(__file__).resolve().parents[2]


def test_the_frozen_publication_verifies():
    """Fails until the frozen results are regenerated with the episode tables verify recomputes from."""
    report = verify(ROOT / "results")
    assert report.ok, report.failures[:5]
    assert report.counts["recomputed"] > 1000 and report.counts["traced"] > 30


@pytest.mark.slow
def test_counts_are_by_kind_and_an_edit_lowers_nothing_but_fails(publication, publication_report, tmp_path):
    report = publication_report
    assert report.ok, report.failures[:5]
    assert all(report.counts[k] > 0 for k in ("recomputed", "traced", "identity", "range", "file"))
    # The headline counts published numbers, not checks: each recomputed value and each printed number once.
    assert 0 < report.verified_numbers < report.checked + 10_000
    copy = tmp_path / "pub"
    shutil.copytree(publication, copy)
    path = copy / "results" / "paper" / "insertion" / "results.json"
    payload = json.loads(path.read_text())
    payload["results"]["text"]["escape_k8"][0] += 0.25
    path.write_text(json.dumps(payload))
    # The edit is a results.json number: its recomputation fails it; drawing the figures again checks nothing more.
    assert any("text.escape_k8" in f for f in verify(copy, figures=False).failures)


@pytest.mark.slow
def test_cli_exit_codes_and_summary(publication, tmp_path):
    ok = CliRunner().invoke(app, ["verify", str(publication)])
    assert ok.exit_code == 0, ok.output
    assert "published numbers verified" in ok.output and "0 failed" in ok.output
    copy = tmp_path / "pub"
    shutil.copytree(publication, copy)
    (copy / "results" / "paper" / "insertion" / "scan.parquet").write_bytes(b"not parquet")
    bad = CliRunner().invoke(app, ["verify", str(copy)])
    assert bad.exit_code == 1 and "FAILED" in bad.output


def test_publication_root_is_found_from_the_repository_or_results(publication):
    paper = publication / "results" / "paper"
    for path in (publication, publication / "results", paper):
        assert publication_root(path) == paper


def test_no_publication_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="holds no publication"):
        verify(tmp_path)


@pytest.mark.slow
def test_reproduce_quick_publish_to_writes_a_verifiable_publication(tmp_path):
    result = CliRunner().invoke(app, ["reproduce", "setup", "--quick", "-o", str(tmp_path / "runs"),
                                      "--publish-to", str(tmp_path / "pub")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "pub" / "REPRODUCTION.md").is_file()
    assert (tmp_path / "pub" / "results" / "paper" / "MANIFEST.json").is_file()
    report = verify(tmp_path / "pub")
    assert report.ok, report.failures[:5]
