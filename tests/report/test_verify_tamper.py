"""The tamper suite: single edits to a scratch publication, each of which ``verify`` must catch.

One quick publication (insertion, breadth, cost) is built per test session; each case copies
it, makes one edit, and (like an attacker who knows the format) re-hashes every manifest,
unless the edit is to the file listing itself. Every case must fail with a message that
names the edited file and the number.
"""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path
from typing import Callable

import pandas as pd
import pytest

from probecommit.report import manifest
from probecommit.report.verify import verify

pytestmark = pytest.mark.slow

Edit = Callable[[Path], list[str]]


@pytest.fixture
def pub(publication, tmp_path) -> Path:
    shutil.copytree(publication, tmp_path / "pub")
    return tmp_path / "pub"


def paper_root(pub: Path) -> Path:
    return pub / "results" / "paper"


def rehash(pub: Path) -> None:
    """What an attacker does after an edit: every listed file's sha256 updated (listings kept)."""
    root = paper_root(pub)
    for path in [*root.glob("*/MANIFEST.json"), root / "MANIFEST.json"]:
        data = json.loads(path.read_text())
        data["sha256"] = {n: manifest.sha256_file(path.parent / n) for n in data["sha256"] if (path.parent / n).is_file()}
        path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")


# ----------------------------------------------------------------------------- edit helpers


def edit_results(study: str, path: list, value, expect: list[str] | None = None) -> Edit:
    """Set one results.json value; the failure names the study's file and the new number (or ``expect``:
    a changed seed or setting shows in the numbers recomputed with it)."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / study / "results.json"
        payload = json.loads(f.read_text())
        node = payload["results"]
        for part in path[:-1]:
            node = node[part]
        node[path[-1]] = value(node[path[-1]]) if callable(value) else value
        f.write_text(json.dumps(payload))
        shown = node[path[-1]]
        return expect or [f"{study}/", str(shown[0] if isinstance(shown, list) else shown)]
    return edit


def edit_text(rel: str, pattern: str, replace: Callable[[re.Match], str], name: str | None = None) -> Edit:
    """Replace the first match of ``pattern`` in a published text file."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / rel
        text = f.read_text()
        m = re.search(pattern, text, flags=re.M)
        assert m, f"{pattern!r} not in {rel}"
        new = replace(m)
        f.write_text(text[:m.start()] + new + text[m.end():])
        number = re.findall(r"[-+]?\d+(?:\.\d+)?", new)
        return [name or Path(rel).name, *(number[:1])]
    return edit


def edit_parquet(rel: str, column: str, row: int, value) -> Edit:
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / rel
        table = pd.read_parquet(f)
        old = table.loc[row, column]
        table.loc[row, column] = value(old) if callable(value) else value
        table.to_parquet(f, index=False)
        return [Path(rel).name]
    return edit


def bump(x: float) -> float:
    return float(x) + 0.0123


def swap_lines(rel: str, first: int) -> Edit:
    """Swap two adjacent table rows (lines ``first`` and ``first + 1``, 0-based) of a text file."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / rel
        lines = f.read_text().splitlines(keepends=True)
        lines[first], lines[first + 1] = lines[first + 1], lines[first]
        f.write_text("".join(lines))
        return [Path(rel).name, f"line {first + 1}"]
    return edit


def swap_parquet_rows(rel: str) -> Edit:
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / rel
        table = pd.read_parquet(f)
        order = list(range(len(table)))
        order[0], order[1] = order[1], order[0]
        table.iloc[order].reset_index(drop=True).to_parquet(f, index=False)
        return [Path(rel).name, "row 0"]
    return edit


def md_number(rel: str, anchor: str, to: Callable[[str], str]) -> Edit:
    """Change the first decimal number after ``anchor`` in a text file."""
    return edit_text(rel, re.escape(anchor) + r"[^\d+-]*([-+]?\d+\.\d+)",
                     lambda m: m.group(0)[:m.start(1) - m.start(0)] + to(m.group(1)))


def plus(text: str) -> str:
    return f"{float(text) + 0.011:.{len(text.split('.')[1])}f}"


def reproduction_md(pattern: str, replace: Callable[[re.Match], str]) -> Edit:
    return edit_text("../../REPRODUCTION.md", pattern, replace, name="REPRODUCTION.md")


def paper_value_as_ours(pub: Path) -> list[str]:
    """A REPRODUCTION.md "ours" cell set to the paper's value on its row."""
    f = pub / "REPRODUCTION.md"
    text = f.read_text()
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and re.fullmatch(r"\d\.\d{3}", cells[1]) and re.match(r"\d\.\d{3}\b", cells[2]) \
                and cells[1] != cells[2][:5]:
            new_line = line.replace(f"| {cells[2][:5]}", f"| {cells[1]}", 1)
            f.write_text(text.replace(line, new_line, 1))
            return ["REPRODUCTION.md", cells[1]]
    raise AssertionError("no paper/ours row")


def delete(rel: str) -> Edit:
    def edit(pub: Path) -> list[str]:
        (paper_root(pub) / rel).unlink()
        return [Path(rel).name]
    return edit


def add_file(rel: str) -> Edit:
    def edit(pub: Path) -> list[str]:
        (paper_root(pub) / rel).write_text("0.5\n")
        return [Path(rel).name]
    return edit


def copy_figure(src: str, dst: str) -> Edit:
    def edit(pub: Path) -> list[str]:
        shutil.copy(paper_root(pub) / src, paper_root(pub) / dst)
        return [Path(dst).name, "digest" if dst.endswith(".png") else "drawn again"]
    return edit


def copy_restamped(src: str, dst: str) -> Edit:
    """A figure copied over another and stamped with the other's data digest (only drawing it again tells)."""
    def edit(pub: Path) -> list[str]:
        target = paper_root(pub) / dst
        digest = manifest.png_data_digest(target)
        shutil.copy(paper_root(pub) / src, target)
        manifest.stamp_png(target, digest)
        return [Path(dst).name, "drawn again"]
    return edit


#: Cases that need the figures drawn again (the rest run verify without, for time).
FIGURE_CASES = {"figure-pdf-copied-from-another-study", "figure-png-copied-with-its-stamp-rewritten",
                "figure-decision-redrawn", "figure-scan-section-redrawn", "figure-decisive-tap-redrawn"}


def nan_rate(pub: Path) -> list[str]:
    return edit_results("insertion", ["table_faults", "boundary", "fail", 0], math.nan)(pub)


def nan_traced(pub: Path) -> list[str]:
    """Inf in a number that is traced only (the re-split pool's size)."""
    return edit_results("insertion", ["resplits", "pool"], math.inf)(pub)


def edit_rows(rel: str, where: Callable[[pd.DataFrame], pd.Series], column: str, value, every: bool = False) -> Edit:
    """Change ``column`` in the first stored row ``where`` selects (or in every one: an edit consistent across
    the rows of one margin, say); the failure names the file."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / rel
        table = pd.read_parquet(f)
        rows = table.index[where(table)]
        assert len(rows), f"no row of {rel} to edit"
        rows = rows if every else rows[:1]
        table.loc[rows, column] = [value(v) if callable(value) else value for v in table.loc[rows, column]]
        table.to_parquet(f, index=False)
        return [Path(rel).name]
    return edit


def first_margin(calibration: str) -> Callable[[pd.DataFrame], pd.Series]:
    """The stored margin rows of the largest margin the search read (its first): predicted set to 1 there, the
    search stops at it, so the published margin no longer follows."""
    def where(t: pd.DataFrame) -> pd.Series:
        rows = (t.calibration == calibration) & (t.request == "margin")
        return rows & (t.gamma == t.loc[rows, "gamma"].max())
    return where


def request(calibration: str, name: str, k: int | None = None) -> Callable[[pd.DataFrame], pd.Series]:
    return lambda t: ((t.calibration == calibration) & (t.request == name) & (t.status == "ok")
                      & (t.k == (k if k is not None else t.k)))


def reproduction_json(field: str) -> Edit:
    """A wall time or an engine-query count edited in reproduction.json; the failure names REPRODUCTION.md's
    number for it, formatted as the ledger records it."""
    def edit(pub: Path) -> list[str]:
        from probecommit.report.ledger import format_value, read

        f = paper_root(pub) / "reproduction.json"
        data = json.loads(f.read_text())
        if field == "wall_s":
            data["wall_s"]["insertion"] = data["wall_s"]["insertion"] + 600.0
            key, value = "reproduction:wall_s.insertion", data["wall_s"]["insertion"]
        else:
            engine = next(iter(data["engine_calls"]["insertion"]))
            data["engine_calls"]["insertion"][engine] += 7
            key, value = f"reproduction:engine_calls.insertion.{engine}", data["engine_calls"]["insertion"][engine]
        f.write_text(json.dumps(data))
        entry = next(e for e in read(paper_root(pub)) if e.key == key)
        return ["REPRODUCTION.md", format_value(value, entry.fmt)]
    return edit


def claims_status(pub: Path) -> list[str]:
    """A claim that differs marked reproduced in claims.json (its counts left alone)."""
    f = paper_root(pub) / "claims.json"
    data = json.loads(f.read_text())
    cid = next(c for c, e in data["claims"].items() if e["status"] != "reproduced")
    data["claims"][cid]["status"] = "reproduced"
    f.write_text(json.dumps(data, indent=1) + "\n")
    return ["claims.json", cid]


def ledger_entry(change: str) -> Edit:
    """One published-numbers ledger entry re-keyed, or its last entries dropped (their numbers then unaccounted for)."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / "published_numbers.json"
        data = json.loads(f.read_text())
        numbers = [e for e in data["numbers"] if e["fmt"] != "literal"]
        if change == "key":
            numbers[0]["key"] += "x"
            expected = ["REPRODUCTION.md", numbers[0]["text"], numbers[0]["key"]]
        else:
            dropped = numbers[-1]
            data["numbers"] = [e for e in data["numbers"] if e is not dropped]
            expected = ["REPRODUCTION.md", dropped["text"]]
        f.write_text(json.dumps(data, indent=1) + "\n")
        return expected
    return edit


def infeasible_truth(pub: Path) -> list[str]:
    """One feasible grasp instance of the sign count's stored rows marked infeasible (all its rows)."""
    f = paper_root(pub) / "breadth" / "sign_flip_rows.parquet"
    table = pd.read_parquet(f)
    instance = table.loc[table["feasible"], "instance_id"].iloc[0]
    table.loc[table["instance_id"] == instance, "feasible"] = False
    table.to_parquet(f, index=False)
    return ["breadth/results.json", "sign_flip_over_truths.grasp", "sign_flip_rows.parquet"]


# Each case: (id, edit, rehash). ``rehash`` False: the attacker left the manifests alone.
CASES: list[tuple[str, Edit, bool]] = [
    ("json-recomputed-point", edit_results("insertion", ["table_testc", "escape_random_k8", "old", 0], bump), True),
    ("json-interval-bound", edit_results("insertion", ["table_insertion", "A.cover_k5", 1], lambda v: v - 0.01), True),
    ("json-paired-difference", edit_results("insertion", ["table_faults", "boundary", "paired_fix", 0], bump), True),
    ("json-threshold", edit_results("insertion", ["table_insertion", "thresholds_random", "8"], bump), True),
    ("json-auc", edit_results("insertion", ["table_faults", "boundary", "surprise_auc"], bump), True),
    ("json-resplit-mean", edit_results("insertion", ["resplits", "level_mean_sd", 0], bump), True),
    ("json-changed-seed", edit_results("insertion", ["setup", "bootstrap", "seed"], lambda s: s + 1,
                                                    ["insertion/results.json", "episodes.parquet gives"]), True),
    ("json-changed-config-alpha", edit_results("insertion", ["setup", "alpha"], 0.3,
                                                           ["insertion/results.json", "thresholds_random", "episodes.parquet gives"]), True),
    ("json-changed-config-sigma", edit_results("insertion", ["setup", "sigma"], 0.7), True),
    ("json-integer-count", edit_results("insertion", ["scan", "scans"], lambda n: n + 1), True),
    ("json-nan-rate", nan_rate, True),
    ("json-inf-traced-only", nan_traced, True),
    ("json-breadth-row", edit_results("breadth", ["table_II", "push1d", "probe_robust"], bump), True),
    ("json-cost-price", edit_results("cost", ["pricing", 0, "blind_above"], bump), True),
    ("json-cost-price-by-name", edit_results("cost", ["prices", "push1d", "blind_above"], bump), True),
    ("json-fault-signature-point", edit_results("insertion", ["fault_signatures", "prior", "1", "failure"], bump), True),
    ("json-robot-sweep-by-size", edit_results("robot", ["prior_by_mm", "12", "escape"], bump), True),
    ("json-robot-pooled-optimism", edit_results("robot", ["optimism_pooled"], bump), True),
    ("claims-status", claims_status, True),
    ("ledger-key", ledger_entry("key"), True),
    ("ledger-entry-dropped", ledger_entry("drop"), True),
    ("parquet-episode-cell", edit_parquet("insertion/episodes.parquet", "realized", 0, lambda v: 1.0 - v), True),
    ("parquet-fault-episode-cell", edit_parquet("insertion/faults_episodes.parquet", "escaped", 0, lambda v: not v), True),
    ("parquet-derived-cell", edit_parquet("insertion/fault_signatures.parquet", "failure", 0, bump), True),
    ("parquet-swapped-rows", swap_parquet_rows("insertion/fault_signatures.parquet"), True),
    ("parquet-breadth-episode", edit_parquet("breadth/breadth_episodes.parquet", "realized", 0, bump), True),
    ("parquet-table2-cell", edit_parquet("breadth/table_II_breadth.parquet", "blind_bayes", 1, bump), True),
    ("parquet-curve-cell", edit_parquet("breadth/budget_curves.parquet", "mean", 0, bump), True),
    ("parquet-sign-flip-feasibility", infeasible_truth, True),
    ("json-sign-flip-count", edit_results("breadth", ["sign_flip_over_truths", "grasp", "n_improve"], lambda n: n + 1), True),
    ("parquet-scan-cell", edit_parquet("insertion/scan.parquet", "offset", 0, bump), True),
    ("md-cell", md_number("insertion/table_V_testc.md", "| escape_random_k8 | ", plus), True),
    ("tex-cell", md_number("insertion/table_V_testc.tex", "escape\\_random\\_k8 & ", plus), True),
    ("md-rounded-differently", md_number("insertion/table_VIII_faults.md", "| boundary | ", lambda t: f"{float(t):.2f}"), True),
    ("md-swapped-rows", swap_lines("insertion/table_V_testc.md", 4), True),
    ("md-note-number", md_number("insertion/table_IV_insertion.md", "distribution-free margin = ", plus), True),
    ("md-breadth-paper-value", edit_text("breadth/table_II_breadth.md", r"\(paper, k=\d+\) \| m \| (\d\.\d{3})",
                                          lambda m: m.group(0)[:-5] + plus(m.group(1))), True),
    ("json-robot-count", edit_results("robot", ["n_covered"], lambda n: n - 1), True),
    ("parquet-robot-episode", edit_parquet("robot/robot_episodes.parquet", "aim_error", 0, bump), True),
    ("md-robot-cell", md_number("robot/table_VII_hardware_simulated_rig.md", "| 1 | ", plus), True),
    ("md-pricing-cell", md_number("cost/table_pricing.md", "| push1d | ", plus), True),
    ("reproduction-ours-to-paper", paper_value_as_ours, True),
    ("reproduction-prose-number", reproduction_md(r"\(failure (\d\.\d{3})\)", lambda m: f"(failure {plus(m.group(1))})"), True),
    ("reproduction-integer", reproduction_md(r"over (\d+) subsets", lambda m: f"over {int(m.group(1)) + 4} subsets"), True),
    ("reproduction-paper-value", reproduction_md(r"\| fitted delta \(mm\) \| \+(\d\.\d{3})",
                                                  lambda m: f"| fitted delta (mm) | +{plus(m.group(1))}"), True),
    ("reproduction-wall-time", reproduction_md(r"insertion (\d+) s,", lambda m: f"insertion {int(m.group(1)) + 60} s,"), True),
    ("reproduction-json-wall", reproduction_json("wall_s"), True),
    ("reproduction-json-engine-calls", reproduction_json("engine_calls"), True),
    ("report-html-number", edit_text("report.html", r"<td>(\d\.\d{3})</td>", lambda m: f"<td>{plus(m.group(1))}</td>"), True),
    ("figure-copied-from-another-study", copy_figure("cost/fig_pricing.png", "breadth/fig_breadth_budget.png"), True),
    ("figure-pdf-copied-from-another-study", copy_figure("cost/fig_pricing.pdf", "breadth/fig_breadth_budget.pdf"), True),
    ("figure-png-copied-with-its-stamp-rewritten", copy_restamped("cost/fig_pricing.png", "breadth/fig_breadth_budget.png"),
     True),
    ("json-calibrated-cost", edit_results("insertion", ["table_insertion", "B.cost_table", 2, "failure"], bump), True),
    ("json-calibrated-difference", edit_results("insertion", ["table_insertion", "B.cost_differences", 0, "lo"], bump), True),
    ("json-table3-calibrated-interval", edit_results("insertion", ["table_audit", "table", 0, "optimism_lo_calibrated"],
                                                     lambda v: v - 0.01), True),
    ("json-table3-original-interval", edit_results("insertion", ["table_audit", "table", 0, "coverage_hi_original"],
                                                   lambda v: v - 0.01), True),
    ("json-margin", edit_results("insertion", ["table_insertion", "margin_cover"], bump), True),
    ("json-simultaneous-threshold", edit_results("insertion", ["table_insertion", "simultaneous_random"], bump), True),
    ("json-testc-set-margin", edit_results("insertion", ["table_testc", "failure_cover_k5_setcal_margin", "old"], bump), True),
    ("json-gates-area", edit_results("insertion", ["gates", "summary", 0, "area"], bump), True),
    ("json-gates-pool", edit_results("insertion", ["gates", "summary", 1, "n_committed"], lambda n: n + 1), True),
    ("json-gates-gamma", edit_results("insertion", ["gates", "info", "gamma"], bump), True),
    ("json-gates-surprise-table", edit_results("insertion", ["gates", "info", "surprise", 0, "n_covered"],
                                               lambda n: n + 1, ["insertion/results.json", "gates.info.surprise.0.n_covered"]),
     True),
    ("json-robust-arm", edit_results("insertion", ["robust", "deployed", "failure", 0], bump), True),
    ("json-robust-tuning", edit_results("insertion", ["robust", "tuning", 0, "failure"], bump), True),
    ("json-robot-first-resolved", edit_results("robot", ["boundary_first_resolved_mm"], lambda v: (v or 0.0) + 1.0), True),
    ("parquet-commits-set-margin", edit_rows("insertion/commits.parquet", request("cover", "set_margin", 5), "realized",
                                             lambda v: 1.0 - v), True),
    ("parquet-commits-margin-consistent", edit_rows("insertion/commits.parquet", first_margin("random"), "predicted", 1.0,
                                                    every=True), True),
    ("parquet-commits-optimism", edit_rows("insertion/commits.parquet", request("cover", "optimism"), "realized",
                                           lambda v: 1.0 - v, every=True), True),
    ("parquet-commits-gates-raw", edit_rows("insertion/commits.parquet", request("gates", "raw"), "predicted", bump), True),
    ("parquet-commits-gates-adjusted", edit_rows("insertion/commits.parquet", request("gates", "adjusted"), "predicted",
                                                 lambda v: 0.0, every=True), True),
    ("parquet-gates-curve-cell", edit_parquet("insertion/gates_curves.parquet", "failure", 0, bump), True),
    ("parquet-coverage-vs-nominal", edit_parquet("insertion/coverage_vs_nominal.parquet", "cluster_coverage", 0, bump), True),
    ("parquet-robust-tuning-row", edit_rows("insertion/robust_episodes.parquet", lambda t: t.part == "tuning", "realized",
                                            lambda v: 1.0 - v), True),
    ("parquet-robust-arm-row", edit_rows("insertion/robust_episodes.parquet", lambda t: t.part == "deployed", "realized",
                                         lambda v: 1.0 - v), True),
    ("parquet-robot-sweep-replay", edit_rows("robot/fault_sweep_episodes.parquet", lambda t: t["size"].notna(),
                                             "covered", lambda v: not v), True),
    ("parquet-robot-deployed-replay", edit_rows("robot/fault_sweep_episodes.parquet", lambda t: t["size"].isna(),
                                                "predicted", bump), True),
    ("figure-decision-redrawn", copy_restamped("insertion/fig_7_signatures.png", "insertion/fig_6_decision.png"), True),
    ("figure-scan-section-redrawn", copy_restamped("insertion/fig_7_signatures.png",
                                                   "insertion/fig_4a_teaser_scan_section.png"), True),
    ("figure-decisive-tap-redrawn", copy_restamped("insertion/fig_7_signatures.png",
                                                   "insertion/fig_4b_teaser_decisive_tap.png"), True),
    ("parquet-decisive-tap-cell", edit_parquet("insertion/decisive_tap.parquet", "z", 0, lambda v: v + 3.0), True),
    ("parquet-scan-grid-cell", edit_parquet("insertion/scan_grid.parquet", "reading", 0, lambda v: v + 3.0), True),
    ("deleted-stored-commits-rehashed", delete("insertion/commits.parquet"), True),
    ("deleted-stored-sweeps-rehashed", delete("robot/fault_sweep_episodes.parquet"), True),
    ("deleted-file", delete("insertion/table_III_audit.tex"), False),
    ("deleted-table-rehashed", delete("insertion/table_V_testc.md"), True),
    ("added-file", add_file("insertion/extra_table.md"), False),
    ("deleted-study-manifest", delete("cost/MANIFEST.json"), False),
    ("deleted-publication-manifest", delete("MANIFEST.json"), False),
    ("deleted-reproduction-md", delete("../../REPRODUCTION.md"), False),
]


def test_the_scratch_publication_verifies(publication_report):
    report = publication_report
    assert report.ok, report.failures[:5]
    assert report.counts["recomputed"] > 500 and report.counts["traced"] >= 20
    assert report.verified_numbers > 1000


def test_the_suite_has_thirty_kinds():
    assert len({name for name, _, _ in CASES}) == len(CASES) >= 30


@pytest.mark.parametrize("name,edit,again", CASES, ids=[c[0] for c in CASES])
def test_a_single_edit_fails_verify_naming_the_file_and_number(pub, name, edit, again):
    expected = edit(pub)
    if again:
        rehash(pub)
    failures = verify(pub, figures=name in FIGURE_CASES).failures
    assert failures, f"{name}: verify passed"
    assert any(all(part in f for part in expected) for f in failures), (name, expected, failures[:6])
