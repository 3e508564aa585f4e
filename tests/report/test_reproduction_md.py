"""REPRODUCTION.md: every number printed from a key, in reading order, and the claims' statuses counted."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from probecommit.report import ledger
from probecommit.report.publish import write_reproduction_md
from probecommit.report.reproduction_md import MD_FILE, PROSE, Doc
from probecommit.studies import paper_values
from probecommit.studies.claims import EXPERIMENTS, STATUSES

DECIMAL = re.compile(r"(?<![\w.])[+-]?\d+\.\d+")


def unrecorded_decimals(text: str, entries: list[ledger.Entry]) -> list[str]:
    """Decimal numbers in ``text`` that no ledger entry accounts for (code spans and Table I's
    configuration text aside)."""
    covered: set[int] = set()
    cursor = 0
    for e in entries:
        at = text.find(e.text, cursor)
        if at >= 0:
            covered.update(range(at, at + len(e.text)))
            cursor = at + len(e.text)
    skip = {i for m in re.finditer(r"`[^`]*`", text) for i in range(m.start(), m.end())}
    setup = re.search(r"(?s)## The task families.*?(?=\n## |\Z)", text)
    if setup:
        skip.update(range(setup.start(), setup.end()))
    return [text[max(0, m.start() - 40):m.end()] for m in DECIMAL.finditer(text)
            if m.start() not in skip and not set(range(m.start(), m.end())) <= covered]


def unnamed_experiments_tried(text: str, claims: dict) -> list[str]:
    """Experiments an unexplained item was tested by (not holding) that its line in "Where ours differs" does not
    name: a reviewer must see what was ruled out."""
    lines = {line.split("`")[1]: line for line in text.splitlines() if line.startswith("- `")}
    missing = []
    for cid, c in claims["claims"].items():
        if c["status"] != "differs, unexplained":
            continue
        held = set((c.get("experiment") or "").split(", "))
        for candidate in c.get("explain_candidates", []):
            if candidate not in held and candidate in EXPERIMENTS and not re.search(
                    rf"\b{re.escape(candidate.split('[')[0])}\b", lines[cid]):
                missing.append(f"{cid}: {candidate}")
    return missing


def test_the_frozen_reproduction_md_names_every_experiment_tried_for_an_unexplained_item():
    repo = Path(__file__).resolve().parents[2]
    claims = json.loads((repo / "results" / "paper" / "claims.json").read_text())
    text = (repo / "REPRODUCTION.md").read_text()
    assert any(c["status"] == "differs, unexplained" for c in claims["claims"].values())
    assert "Tested without support" in text
    assert not unnamed_experiments_tried(text, claims)


def check_publication(repo: Path) -> dict:
    root = repo / "results" / "paper"
    entries = ledger.read(root)
    problems = list(ledger.check(entries, root, {"paper": paper_values.tree()}))
    assert not problems, problems[:5]
    text = (repo / "REPRODUCTION.md").read_text()
    mine = [e for e in entries if e.file == MD_FILE]
    assert not unrecorded_decimals(text, mine), unrecorded_decimals(text, mine)[:5]
    assert not list(ledger.uncovered(entries, root)), list(ledger.uncovered(entries, root))[:5]
    # A number the report's own wording holds is structural (k = 8, Table II): never a decimal result.
    prose = [e.text for e in mine if e.fmt == ledger.LITERAL and e.key == f"{ledger.LITERAL}:{PROSE}"]
    assert prose and not [t for t in prose if DECIMAL.search(t.split("\n")[-1][-12:])]
    header_cells = None
    for line in text.splitlines():  # every table row has its header's number of cells
        if not line.startswith("|"):
            header_cells = None
            continue
        cells = line.count("|") - 1
        header_cells = header_cells or cells
        assert cells == header_cells, line
    claims = json.loads((root / "claims.json").read_text())
    counts = claims["counts"]
    assert counts["total"] == 59 == len(claims["claims"]) == sum(counts[s] for s in STATUSES)
    assert {c["status"] for c in claims["claims"].values()} <= set(STATUSES)
    # The counts printed at the top are claims.json's own.
    first = text.split("## Every item of the paper, compared", 1)[1][:1000]
    rig = claims.get("counts_simulated_rig", {})  # how many of each rest on the simulated rig (a newer claims.json)
    for status in ("reproduced", "missing"):
        suffix = f" ({rig[status]} of them on the simulated rig)" if rig.get(status) else ""
        assert f"**{counts[status]} {status}{suffix}**" in first
    assert not unnamed_experiments_tried(text, claims)
    return claims


def test_doc_records_numbers_in_reading_order_whatever_the_order_they_were_asked_for(tmp_path):
    root = tmp_path / "results" / "paper"
    (root / "gru").mkdir(parents=True)
    (root / "gru" / "results.json").write_text(json.dumps({"results": {"a": 0.25, "b": [1.5, 1.0, 2.0]}}))
    book = ledger.Ledger()
    doc = Doc(root, book, "out.md")
    later = doc.n("gru:results.a")  # asked for first, printed last
    doc.add(f"first {doc.ci('gru:results.b', '.1f')} then {doc.pv('T03-margin.cover')} then {later}; "
            f"{doc.n('gru:results.nothing')}")
    text = doc.text()
    assert text == "first 1.5 [1.0, 2.0] then 0.74 then 0.250; --\n"
    assert [e.key for e in book.entries if e.fmt != ledger.LITERAL] == [
        "gru:results.b.0", "gru:results.b.1", "gru:results.b.2", "paper:T03-margin.cover", "gru:results.a"]
    (root / "out.md").write_text(text)
    assert not list(ledger.check(book.entries, root, {"paper": paper_values.tree()}))
    (root / "out.md").write_text(text.replace("0.250", "0.260"))
    assert any("0.250" in p for p in ledger.check(book.entries, root, {"paper": paper_values.tree()}))


def test_a_partial_publication_counts_every_item_and_says_what_is_missing(tmp_path):
    root = tmp_path / "results" / "paper"
    (root / "gru").mkdir(parents=True)
    (root / "gru" / "results.json").write_text(json.dumps({"results": {
        "pipeline_miss": 0.09, "gru_miss": 0.08, "gru_minus_pipeline": [-0.010, -0.023, 0.001],
        "equivalence_margin": 0.02, "equivalent": False, "seeds": 15}}))
    write_reproduction_md(tmp_path)
    claims = check_publication(tmp_path)
    assert claims["claims"]["T10-gru"]["status"] in ("differs, unexplained", "differs, explained")
    assert claims["claims"]["T10-gru"]["failed"] == ["equivalent"]  # the paper's -0.004 lies inside ours
    assert claims["claims"]["tab:audit"]["status"] == "missing"
    assert claims["counts"]["missing"] == 58
    from probecommit.report.manifest import write_all
    from probecommit.report.verify import verify

    write_all(root)  # the manifests publishing writes last
    assert not [f for f in verify(tmp_path / "results").failures if "claims.json" in f]
    stored = json.loads((root / "claims.json").read_text())
    stored["claims"]["T10-gru"]["status"] = "reproduced"
    (root / "claims.json").write_text(json.dumps(stored))
    assert any("T10-gru" in f for f in verify(tmp_path / "results").failures)


@pytest.mark.slow
def test_a_quick_reproduction_publishes_a_reproduction_md_whose_every_number_traces(tmp_path):
    from probecommit.report.paper import reproduce
    from probecommit.report.publish import publish
    from probecommit.report.verify import verify

    done = reproduce(["all"], tmp_path / "runs", quick=True)
    publish(done["targets"], tmp_path / "repo", timing=done)
    claims = check_publication(tmp_path / "repo")
    assert claims["claims"]["fig:hardware"]["status"] == "missing"  # panel (a) photographs the physical arm
    assert claims["claims"]["fig:decision"]["status"] != "missing"  # generated: fig_6_decision.png
    text = (tmp_path / "repo" / "REPRODUCTION.md").read_text()
    assert "simulated rig" in text and "The machine that produced" not in text
    robot = tmp_path / "repo" / "results" / "paper" / "robot"
    assert "sim. rig" in (robot / "table_VII_hardware_simulated_rig.md").read_text()
    assert json.loads((robot / "results.json").read_text())["results"]["rig"] == "simulated"
    report = verify(tmp_path / "repo" / "results")
    assert report.ok, report.failures[:5]


def test_the_frozen_publication_passes_every_check_a_new_publication_must():
    """The checks run on a quick publication, on the frozen full one (its sentences print more experiments)."""
    check_publication(Path(__file__).resolve().parents[2])
