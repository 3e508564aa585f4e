"""The claims registry and the paper-values table: hand cases that can fail, and the paper's own text."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from probecommit.studies import claims as C
from probecommit.studies import paper_values as P

PAPER_TEX = Path(os.environ.get("PROBECOMMIT_PAPER_TEX", "/work/shared/seed/000_9d0aab961ea060bd.txt"))


@pytest.mark.skipif(not PAPER_TEX.is_file(), reason="the paper's LaTeX source is not on this machine")
def test_every_paper_value_is_printed_in_the_paper():
    text = PAPER_TEX.read_text()
    missing = [f"{key} = {P.PRINTED[key]!r}" for key in P.PRINTED if P.seed_form(key) not in text]
    assert not missing, missing


@pytest.mark.skipif(not PAPER_TEX.is_file(), reason="the paper's LaTeX source is not on this machine")
def test_the_registry_uses_every_label_the_paper_defines():
    labels = set(re.findall(r"\\label\{((?:tab|fig):[a-z]+)\}", PAPER_TEX.read_text()))
    ours = {c.id for c in C.CLAIMS if c.kind != "text"}
    assert labels == ours


def test_paper_values_print_back_exactly():
    for key in P.PRINTED:
        if P.is_number(key):
            from probecommit.report.ledger import format_value

            assert format_value(P.value(key), P.fmt(key)) == P.PRINTED[key], key
    assert P.fmt("tab:audit.optimism_original.1") == "+.3f" and P.value("tab:audit.optimism_calibrated.1") == -0.003
    assert P.fmt("tab:audit.cluster_coverage_original.1") == ".2f" and P.fmt("T23-hardware-guards.pass") == "d"
    with pytest.raises(ValueError):
        P.value("T07-cover-schedule.schedule")


def test_registry_has_the_papers_59_items_in_its_numbering():
    kinds = [c.kind for c in C.CLAIMS]
    assert (kinds.count("table"), kinds.count("figure"), kinds.count("text")) == (8, 7, 44)
    assert len({c.id for c in C.CLAIMS}) == 59
    tables = [c.location.split(" (")[0] for c in C.CLAIMS if c.kind == "table"]
    assert tables == [f"Table {r}" for r in ("I", "II", "III", "IV", "V", "VI", "VII", "VIII")]
    figures = [c.location.split(" (")[0] for c in C.CLAIMS if c.kind == "figure"]
    assert figures == [f"Fig. {n}" for n in range(1, 8)]
    for claim in C.CLAIMS:
        assert "." not in claim.id  # ids are one part of a dotted ledger key
        for key in claim.paper_keys():
            assert key in P.PRINTED, (claim.id, key)
        labels = [c.label for c in claim.comparisons]
        for number, covers in C.explanations(claim):
            assert number in C.EXPERIMENTS, (claim.id, number)
            for prefix in covers or ():  # a cover names comparisons the claim has
                assert any(C.speaks(label, prefix) for label in labels), (claim.id, prefix)


def _lookup(values):
    def lookup(key):
        if key not in values:
            raise KeyError(key)
        return values[key]
    return lookup


def test_inside_near_and_paired_rules_on_hand_values():
    inside = C.Inside("x", "tab:insertion.A_no_probe.est", "s:a")  # paper 0.820
    assert inside.test(_lookup({"s:a": [0.83, 0.76, 0.90]}))
    assert not inside.test(_lookup({"s:a": [0.90, 0.85, 0.95]}))
    near = C.Near("g", "T03-margin.cover", "s:g", 0.02)  # paper 0.74
    assert near.test(_lookup({"s:g": 0.76})) and not near.test(_lookup({"s:g": 0.60}))
    paired = C.Paired("d", ("T41-paired-fixes.boundary", "T41-paired-fixes.boundary_lo", "T41-paired-fixes.boundary_hi"),
                      "s:d")  # paper -0.281 [-0.352, -0.214]: excludes zero, negative
    assert paired.test(_lookup({"s:d": [-0.193, -0.258, -0.130]}))
    assert not paired.test(_lookup({"s:d": [-0.02, -0.06, 0.01]}))  # ours covers zero
    assert not paired.test(_lookup({"s:d": [0.2, 0.1, 0.3]}))  # opposite sign
    not_resolved = C.Paired("p", ("T41-paired-fixes.particles", "T41-paired-fixes.particles_lo",
                                  "T41-paired-fixes.particles_hi"), "s:p")  # paper covers zero
    assert not_resolved.test(_lookup({"s:p": [0.003, -0.026, 0.029]}))


def test_status_is_reproduced_differs_explained_unexplained_or_missing():
    claim = C.Claim("T99-x", "Sec. X", "x", (C.Near("g", "T03-margin.cover", "s:g", 0.02),), explain=("E99",))
    assert C.evaluate(claim, _lookup({"s:g": 0.74}), lambda p: True).status == "reproduced"
    assert C.evaluate(claim, _lookup({}), lambda p: True).status == "missing"
    assert C.evaluate(claim, _lookup({"s:g": 0.60}), lambda p: True).status == "differs, unexplained"
    C.register_experiment(C.Experiment("E99", "test", {"v": "explain:v"}, "value {v:.2f}",
                                       supports=lambda v: v["v"] > 0))
    try:
        assert C.evaluate(claim, _lookup({"s:g": 0.60, "explain:v": 1.0}), lambda p: True).status == "differs, explained"
        # An experiment whose number does not bear the cause out explains nothing.
        assert C.evaluate(claim, _lookup({"s:g": 0.60, "explain:v": -1.0}), lambda p: True).status == \
            "differs, unexplained"
    finally:
        del C.EXPERIMENTS["E99"]
    figure = C.Claim("fig:x", "Fig. 9", "x", (C.Figure("a", "fig_9a_*.png"),))
    assert C.evaluate(figure, _lookup({}), lambda p: False).status == "missing"
    assert C.evaluate(figure, _lookup({}), lambda p: True).status == "reproduced"
    photo = next(c for c in C.CLAIMS if c.id == "fig:hardware")
    assert C.evaluate(photo, _lookup({}), lambda p: True).status == "missing"  # a photograph of the arm


def test_counts_add_up():
    outcomes = {c.id: C.evaluate(c, _lookup({}), lambda p: False) for c in C.CLAIMS}
    counts = C.counts(outcomes)
    assert counts["total"] == 59 == sum(counts[s] for s in C.STATUSES)
    assert counts["missing"] == 59  # nothing resolves in an empty tree


def test_no_result_number_is_typed_into_publishing_prose():
    """Publishing code prints numbers through the ledger only: no decimal inside its string literals."""
    import ast

    import probecommit.report.claims_json as cj
    import probecommit.report.publish as pub
    import probecommit.report.reproduction_md as md

    for module in (pub, md, cj):
        tree = ast.parse(Path(module.__file__).read_text())
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, (ast.Module, ast.FunctionDef, ast.ClassDef)) and n.body
                      and isinstance(n.body[0], ast.Expr)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                found = re.findall(r"(?<![\w.])\d+\.\d+", node.value)
                assert not found, f"{module.__name__}: {found} in {node.value[:80]!r}"
    for claim in C.CLAIMS:  # what the claims table prints about each item
        for text in (claim.what, claim.location, claim.note):
            assert not re.findall(r"(?<![\w.])\d+\.\d+", text), (claim.id, text)


def test_no_experiment_title_sentence_or_claim_text_types_a_decimal_number():
    """Titles and claim descriptions are printed as prose in REPRODUCTION.md; a result or paper value in them
    would be a number typed by hand (it must come from a key, as the experiment's sentence fills it)."""
    decimal = re.compile(r"(?<![\w.])[+-]?\d+\.\d+")
    typed = [f"{n}: {e.title}" for n, e in C.EXPERIMENTS.items() if decimal.search(e.title)]
    typed += [f"{c.id}: {c.what}" for c in C.CLAIMS if decimal.search(c.what)]
    # The sentences' own words (not their keys).
    typed += [f"{n}: {e.template}" for n, e in C.EXPERIMENTS.items()
              if decimal.search(re.sub(r"\{[^}]*\}", "", e.template))]
    assert not typed, typed


#: Each table's registry keys ``tab:<t>.<a>.<b>``: which part names the paper's row (the other, the column, in
#: the registry's order) and the columns kept (a caption's number, or a second value in one cell, is checked
#: only by the test above).
_ROW_PART = {"tab:breadth": (1, ("blind_bayes", "blind_robust", "probe_robust", "delta", "delta_lo", "delta_hi")),
             "tab:audit": (2, None), "tab:insertion": (1, None), "tab:testc": (1, None), "tab:engines": (2, None),
             "tab:hardware": (1, None), "tab:faults": (1, None)}


def _paper_rows(text: str, table: str) -> list[list[str]]:
    """The numbers of each row of the paper's tabular labelled ``table``, as printed, in reading order."""
    body = text.split(f"\\label{{{table}}}", 1)[1]
    body = body.split("\\begin{tabular}", 1)[1].split("\\end{tabular}", 1)[0]
    return [re.findall(r"(?<![\w.])[+-]?\d+(?:\.\d+)?", row) for row in body.split("\\\\")]


def _in_order(values: list[str], row: list[str]) -> bool:
    it = iter(row)
    return all(v in it for v in values)


@pytest.mark.skipif(not PAPER_TEX.is_file(), reason="the paper's LaTeX source is not on this machine")
def test_every_table_value_sits_in_its_row_of_the_paper():
    """A value the paper prints can still be filed under the wrong cell (another arm, k or column): each
    registry row's values must appear, in the registry's column order, in one row of the paper's table."""
    text = PAPER_TEX.read_text()
    for table, (part, columns) in _ROW_PART.items():
        groups: dict[str, list[str]] = {}
        for key, printed in P.PRINTED.items():
            parts = key.split(".")
            if parts[0] != table or len(parts) != 3 or (columns and parts[2] not in columns):
                continue
            if table == "tab:audit" and not parts[2].isdigit():
                continue
            groups.setdefault(parts[part], []).append(printed)
        rows = _paper_rows(text, table)
        assert groups, table
        for name, values in groups.items():
            assert any(_in_order(values, row) for row in rows), (table, name, values)


def test_a_flag_is_printed_beside_its_legend():
    """``{flag:g} = yes`` prints "0 = yes" when the flag is 0; a flag is printed as ``{flag:g}, 1 = yes``."""
    bad = [(n, m.group(0)) for n, e in C.EXPERIMENTS.items()
           for m in re.finditer(r"\{\w+(?::[^}]*)?\}\s*=\s*(?:yes|holds|no)\b", e.template)]
    assert not bad, bad


def test_a_surprise_cell_is_credited_only_to_an_experiment_on_surprise():
    """An experiment explains only what its numbers measure: a surprise AUC cell is never credited to one whose
    title and sentence say nothing of surprise (E7 on Table VIII's boundary row did)."""
    for claim in C.CLAIMS:
        labels = [c.label for c in claim.comparisons if "surprise" in c.label.lower()]
        for number, covers in C.explanations(claim):
            spoken = [lab for lab in labels if covers is None or any(C.speaks(lab, p) for p in covers)]
            e = C.EXPERIMENTS[number]
            text = (e.title + e.template).lower()
            assert not spoken or "surprise" in text or "auc" in text, (claim.id, number, spoken)
