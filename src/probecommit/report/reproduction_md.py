"""REPRODUCTION.md, written from the results tree: every number through the ledger.

Why: a number typed into prose goes stale the moment a table is regenerated. Here the
renderer never holds a result value: it names a key (``"insertion:results.scan.delta"``,
``"paper:T15-scan.delta"``, ``"claims:tab:audit.passed"``), :class:`Doc` resolves it
against the publication root and asks the :class:`~probecommit.report.ledger.Ledger` for
its text, which records ``(file, key, fmt, text)``. ``verify`` re-resolves every entry.

The document opens with the claims registry's status counts and its table of every paper
item, then the differences and the experiments that explain them, then one section per
study. A key that does not resolve prints ``--`` (the claims table then says ``missing``).
"""

from __future__ import annotations

import json
import re
import string
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from probecommit.report.ledger import NUMBER, Ledger, resolve
from probecommit.studies import paper_values
from probecommit.studies.claims import CLAIMS, EXPERIMENTS, STATUSES

#: Where REPRODUCTION.md sits, relative to the publication root ``results/paper``.
MD_FILE = "../../REPRODUCTION.md"
DASH = "--"
#: Why a number in the report's own wording is printed as it stands (a literal, not a result).
PROSE = "the report's own wording (headings, budgets, table numerals, labels)"
#: Why Table I's cells and the machine record are printed as they stand.
CONFIGURATION = "configuration text (the task registry's Table I, the machine record)"
_PLACEHOLDER = re.compile("\x00(\\d+)\x00")


class Doc:
    """A Markdown document whose every number comes from a key (see the module docstring)."""

    def __init__(self, root: str | Path, ledger: Ledger, file: str = MD_FILE) -> None:
        self.root = Path(root)
        self.ledger = ledger
        self.file = file
        self.lines: list[tuple[str, str]] = []
        self.pending: list[tuple[str, Any, str]] = []
        self.trees: dict[str, Any] = {"paper": paper_values.tree()}
        for path in sorted(self.root.glob("*/results.json")):
            self.trees[path.parent.name] = json.loads(path.read_text())
        for name, prefix in (("claims.json", "claims"), ("reproduction.json", "reproduction")):
            if (self.root / name).is_file():
                self.trees[prefix] = json.loads((self.root / name).read_text())

    # ---------------------------------------------------------------- values
    def value(self, key: str) -> Any:
        """The value ``key`` names (KeyError and friends when it names nothing)."""
        return resolve(key, self.root, self.trees)

    def has(self, key: str) -> bool:
        try:
            v = self.value(key)
        except (KeyError, IndexError, ValueError, TypeError, FileNotFoundError):
            return False
        return v is not None and not (isinstance(v, float) and v != v)

    def n(self, key: str, fmt: str = ".3f") -> str:
        """A placeholder for the number under ``key`` (or ``--``); :meth:`text` fills it in reading order.

        Placeholders let a caller compute cells in any order while the ledger records them
        in the order they are printed, which is what ``ledger.check`` relies on.
        """
        if not self.has(key):
            return DASH
        self.pending.append((key, self.value(key), fmt))
        return f"\x00{len(self.pending) - 1}\x00"

    def ci(self, keys: str | Sequence[str], fmt: str = ".3f") -> str:
        """``estimate [lo, hi]`` from a triple key or three keys."""
        if isinstance(keys, str):
            if not self.has(keys):
                return DASH
            v = self.value(keys)
            if not (isinstance(v, list) and len(v) == 3):
                return self.n(keys, fmt)
            keys = [f"{keys}.{i}" for i in range(3)]
        if not all(self.has(k) for k in keys):
            return self.n(keys[0], fmt) if self.has(keys[0]) else DASH
        est, lo, hi = (self.n(k, fmt) for k in keys)
        return f"{est} [{lo}, {hi}]"

    def pv(self, key: str) -> str:
        """A paper value, printed exactly as the paper prints it (``"paper:<key>"``)."""
        if key not in paper_values.PRINTED:
            return DASH
        if not paper_values.is_number(key):
            return paper_values.PRINTED[key]
        self.pending.append((f"paper:{key}", paper_values.value(key), paper_values.fmt(key)))
        return f"\x00{len(self.pending) - 1}\x00"

    def fill(self, template: str, keys: dict[str, str]) -> str:
        """``template``'s fields (``{name:fmt}``) filled from ``keys`` through the ledger."""
        out = []
        for literal, name, spec, _ in string.Formatter().parse(template):
            out.append(literal)
            if name is not None:
                value = self.value(keys[name]) if self.has(keys[name]) else None
                triple = isinstance(value, list) and len(value) == 3
                out.append(self.ci(keys[name], spec or ".3f") if triple else self.n(keys[name], spec or ".3f"))
        return "".join(out)

    # ---------------------------------------------------------------- text
    def add(self, *lines: str, why: str = "") -> None:
        """Append lines. A number in them that is not a placeholder is declared a literal in the
        ledger for ``why`` (default: the report's own wording, headings, budgets and labels)."""
        self.lines.extend((line, why or PROSE) for line in lines)

    def table(self, header: Sequence[str], rows: Iterable[Sequence[str]]) -> None:
        self.add("| " + " | ".join(header) + " |", "|" + "---|" * len(header))
        self.add(*("| " + " | ".join(row) + " |" for row in rows))
        self.add("")

    def text(self) -> str:
        """The document, each placeholder replaced by its number, every number recorded in reading order.

        A number from a key is recorded with its key; any other number (a budget in a heading,
        a table's numeral, configuration text) is declared a literal with the text that leads up
        to it, so ``ledger.check`` finds it in place and ``ledger.uncovered`` accounts for it.
        """
        out: list[str] = []
        for n, (line, why) in enumerate(self.lines):
            text = line + ("\n" if n < len(self.lines) - 1 else "")
            start = 0
            for match in _PLACEHOLDER.finditer(text):
                out.append(self._literals(text[start:match.start()], why))
                key, value, fmt = self.pending[int(match.group(1))]
                out.append(self.ledger.num(self.file, key, value, fmt))
                start = match.end()
            out.append(self._literals(text[start:], why))
        return "".join(out).rstrip() + "\n"

    def _literals(self, chunk: str, why: str) -> str:
        start = 0
        for match in NUMBER.finditer(chunk):
            self.ledger.literal(self.file, chunk[start:match.end()], why)
            start = match.end()
        # Digits inside words ("T06-...", "push2d") are no numbers, but a short number looked up after
        # them could match there: declare the text up to the last such digit so lookups start past it.
        last = max((i for i, c in enumerate(chunk) if c.isdigit() and i >= start), default=-1)
        if last >= 0:
            self.ledger.literal(self.file, chunk[start:last + 1], why)
        return chunk


# ----------------------------------------------------------------------------- the claims


def _count(doc: Doc, status: str, words: str) -> str:
    """``"22 reproduced (4 of them on the simulated rig)"``: a status's count and how many rest on the rig.

    Why: a simulation of a physical-arm claim is not the arm; the opening says how many of each
    count are such, from the registry's ``simulated_rig`` flag (``claims:counts_simulated_rig``).
    """
    text = f"{doc.n('claims:counts.' + status, 'd')} {words}"
    rig = f"claims:counts_simulated_rig.{status}"
    if doc.has(rig) and doc.value(rig):
        text += f" ({doc.n(rig, 'd')} of them on the simulated rig)"
    return text


def claims_section(doc: Doc) -> None:
    """Status counts, the table of every paper item, then each difference with its experiment."""
    if "claims" not in doc.trees:
        return
    c = "claims:counts."
    kinds = {kind: sum(claim.kind == kind for claim in CLAIMS) for kind in ("table", "figure", "text")}
    doc.add("## Every item of the paper, compared", "",
            f"The paper has {doc.n(c + 'total', 'd')} items: {kinds['table']} tables, {kinds['figure']} figures and "
            f"{kinds['text']} numbered quantitative claims in "
            "the text, each an entry of the claims registry (`src/probecommit/studies/claims.py`) with its comparison "
            f"rule. Computed at publish time: **{_count(doc, 'reproduced', 'reproduced')}**, "
            f"**{_count(doc, 'differs, explained', 'differ, explained by an experiment')}**, "
            f"**{_count(doc, 'differs, unexplained', 'differ, unexplained')}**, "
            f"**{_count(doc, 'missing', 'missing')}**. "
            "The statuses are in `results/paper/claims.json`; a comparison on the simulated rig is marked so.", "")
    rows = []
    for claim in CLAIMS:
        base = f"claims:claims.{claim.id}"
        status = doc.value(f"{base}.status") if doc.has(f"{base}.status") else "missing"
        experiment = doc.value(f"{base}.experiment") if doc.has(f"{base}.experiment") else None
        where = claim.location + (" (simulated rig)" if claim.simulated_rig else "")
        passed = (f"{doc.n(base + '.passed', 'd')} of {doc.n(base + '.total', 'd')}" if claim.comparisons else DASH)
        rows.append([f"`{claim.id}`", where, claim.what, passed, status + (f" ({experiment})" if experiment else "")])
    doc.table(["item", "where in the paper", "what", "comparisons holding", "status"], rows)
    doc.add("### Where ours differs, and why", "")
    for claim in CLAIMS:
        base = f"claims:claims.{claim.id}"
        status = doc.value(f"{base}.status") if doc.has(f"{base}.status") else "missing"
        if status == "reproduced":
            continue
        failed = doc.value(f"{base}.failed") if doc.has(f"{base}.failed") else []
        head = f"- `{claim.id}` ({claim.location}), {status}"
        if status == "missing":
            why = doc.value(f"{base}.unresolved") if doc.has(f"{base}.unresolved") else []
            if claim.physical:
                doc.add(f"{head}: it exists only on the paper's physical arm"
                        + (" (the simulated rig's counterpart is in its section, labelled so)." if claim.simulated_rig
                           else "."))
            else:
                doc.add(f"{head}: not computed here ({'; '.join(map(str, why))}).")
            continue
        line = f"{head}: {', '.join(failed)} differ{'s' if len(failed) == 1 else ''}."
        numbers = doc.value(f"{base}.experiment") if doc.has(f"{base}.experiment") else None
        for number in (numbers or "").split(", "):
            if number in EXPERIMENTS:
                e = EXPERIMENTS[number]
                line += f" **{e.number}, {e.title}:** {doc.fill(e.template, dict(e.keys))}"
        if numbers and status == "differs, unexplained":
            line += " The experiments above speak to part of the difference only; the rest is unexplained."
        if status == "differs, unexplained":
            line += _tried(doc, base, numbers)
        doc.add(line)
    doc.add("")


def _tried(doc: Doc, base: str, holding: str | None) -> str:
    """The experiments an unexplained item was tested by that support no cause (their rules failed on our data),
    by number and title (an experiment run once per cell, ``E17[<cell>]``, once, with its count of cells): a
    reviewer sees what was ruled out, and finds each one's numbers in explain.md."""
    candidates = doc.value(f"{base}.explain_candidates") if doc.has(f"{base}.explain_candidates") else []
    held = set((holding or "").split(", "))
    by_number: dict[str, list[str]] = {}
    for c in map(str, candidates):
        if c not in held and c in EXPERIMENTS:
            by_number.setdefault(c.split("[")[0], []).append(c)
    if not by_number:
        return ""
    parts = [f"{n}, {EXPERIMENTS[ids[0]].title}" if ids == [n] else
             f"{n} on {len(ids)} cell{'s' if len(ids) > 1 else ''}, e.g. {ids[0]}, {EXPERIMENTS[ids[0]].title}"
             for n, ids in by_number.items()]
    return (" Tested without support (their rules in `docs/decisions.md`, their numbers in "
            "`results/paper/explain/explain.md`): " + "; ".join(parts) + ".")


# ----------------------------------------------------------------------------- the machine


def machine_section(doc: Doc) -> None:
    r = "reproduction:"
    if "reproduction" not in doc.trees:
        return
    tree = doc.trees["reproduction"]
    walls = ", ".join(f"{t} {doc.n(f'{r}wall_s.{t}', '.0f')} s" for t in tree.get("wall_s", {}))
    doc.add(f"Wall time of the last reproduction, per target: {walls}.")
    calls = tree.get("engine_calls") or {}
    if calls:
        parts = [f"{t}: " + ", ".join(f"{e} {doc.n(f'{r}engine_calls.{t}.{e}', 'd')}" for e in sorted(c))
                 for t, c in calls.items() if c]
        doc.add("Engine queries recorded in the run manifests (each a distinct, cached query; one engine cache is "
                "shared across every run and replay of a reproduction): " + "; ".join(parts) + ".")
    m = tree.get("machine")
    if m:
        doc.add(f"These results were produced on `{m.get('cpu', '?')}` ({doc.n(r + 'machine.cores', 'd')} logical "
                f"cores, widest vector unit `{m.get('vector', 'not recorded')}`, `{m.get('platform', '?')}`, Python "
                f"`{m.get('python', '?')}`, NumPy `{m.get('numpy', '?')}`). NumPy and torch pick their vector routines "
                "by the CPU, so on a CPU with other vector units a few values can differ in the last binary digit; "
                "the GRU's training amplifies such digits over its steps, so its table can differ in the second or third "
                "significant digit (measured on two hosts: docs/decisions.md, \"The GRU across CPUs\"). `verify` "
                "recomputes every GRU number but the training loss from the stored episodes, so it checks a "
                "reproduction made on any CPU.", why=CONFIGURATION)
    else:
        doc.add("The machine that produced these results was not recorded (their `reproduction.json` predates the "
                "record); a reproduction now records it.")
    doc.add("")


# ----------------------------------------------------------------------------- per-study sections


def _pair_rows(doc: Doc, rows: Iterable[tuple[Any, ...]]) -> list[list[str]]:
    """``[label, paper, ours]`` rows from ``(label, paper key, our key[, format])``."""
    out = []
    for label, paper_key, ours, *fmt in rows:
        out.append([label, doc.pv(paper_key) if paper_key else DASH, doc.ci(ours, *fmt)])
    return out


def insertion_section(doc: Doc) -> None:
    """The MuJoCo insertion study: Tables III, IV, V, VIII, the scan, gates, robust filters, re-splits."""
    if "insertion" not in doc.trees:
        return
    i = "insertion:results."
    doc.add("## MuJoCo insertion (paper Sec. V-A to V-C, VI)", "",
            "Generated by `probecommit reproduce insertion` from `configs/paper/insertion.yaml` (taps cached per "
            "instance and position, pegs per instance and aim).", "")
    for part in (_scan_and_cover, _table_iv, _table_iii, _table_v, _table_viii, _robust_filters, _resplits):
        part(doc, i)
    if doc.has(f"{i}gates.summary"):
        gates_table(doc, i)
    figures = doc.trees["insertion"].get("figures") or {}
    if figures:
        doc.add("Figures: " + ", ".join(f"`{Path(p).name}`" for p in figures.values()) + ".", "")




#: The header of the insertion section's tables.
_HEAD = ["quantity", "paper", "ours [95% CI]"]


def _scan_and_cover(doc: Doc, i: str) -> None:
    """The boundary scan and the cover schedule search (development instances)."""
    doc.add("### Boundary scan and cover schedule (development instances)", "")
    doc.table(_HEAD, _pair_rows(doc, [("fitted delta (mm)", "T15-scan.delta", f"{i}scan.delta"),
                                     ("boundary shift vs deployed (mm)", "T15-scan.shift", f"{i}scan.shift_vs_deployed_mm"),
                                     ("SD over scans (mm)", None, f"{i}scan.sd", ".4f"),
                                     ("scans", "T15-scan.scans", f"{i}scan.scans", "d")]))
    if doc.has(f"{i}cover.winner"):
        winner = ", ".join(doc.n(f"{i}cover.winner.{j}", "g") for j in range(len(doc.value(f"{i}cover.winner"))))
        frozen = ", ".join(doc.n(f"{i}cover.frozen.{j}", "g") for j in range(len(doc.value(f"{i}cover.frozen"))))
        doc.add(f"Cover schedule: paper {paper_values.PRINTED['T07-cover-schedule.schedule']} mm; our search's winner "
                f"[{winner}] mm over {doc.n(i + 'cover.candidates', 'd')} subsets (failure "
                f"{doc.n(i + 'cover.winner_failure')}); frozen in the protocol: [{frozen}] mm.", "")


def _table_iv(doc: Doc, i: str) -> None:
    """Table IV: insertion failure by split and calibration setting."""
    doc.add("### Insertion failure by split and calibration setting (Table IV)", "")
    cost = f"{i}table_insertion.B.cost_table."
    rows = [("A, no probe (Blind-Bayes)", "tab:insertion.A_no_probe.est", f"{i}table_insertion.A.no_probe"),
            ("A, cover k=5", "tab:insertion.A_cover_k5.est", f"{i}table_insertion.A.cover_k5")]
    for j, (label, name) in enumerate((("B, Blind-Robust", "B_blind_robust"), ("B, cover k=5", "B_cover_k5"),
                                       ("B, cover k=5, set cal.", "B_cover_k5_setcal"),
                                       ("B, cover k=5, set cal. + margin", "B_cover_k5_setcal_margin"))):
        rows.append((label, f"tab:insertion.{name}.est", [f"{cost}{j}.failure", f"{cost}{j}.failure_lo",
                                                          f"{cost}{j}.failure_hi"]))
    rows += [("margin gamma, cover", "T03-margin.cover", f"{i}table_insertion.margin_cover"),
             ("margin gamma, random", "T03-margin.random", f"{i}table_insertion.margin_random"),
             ("distribution-free margin, cover", "T04-distribution-free-margin.cover",
              f"{i}table_insertion.distribution_free_margin_cover"),
             ("t_5, cover", "T02-t5-cover.t5", f"{i}table_insertion.thresholds_cover.5")]
    d = f"{i}table_insertion.B.cost_differences."
    for j, name in enumerate(("full", "set", "margin")):
        rows.append((f"paired failure increase, {name}", f"T13-cost-of-calibration.{name}",
                     [f"{d}{j}.difference", f"{d}{j}.lo", f"{d}{j}.hi"]))
    doc.table(_HEAD, _pair_rows(doc, rows))


def _table_iii(doc: Doc, i: str) -> None:
    """Table III: the insertion audit, Split B, random probes."""
    doc.add("### Insertion audit, Split B, random probes (Table III)", "")
    rows = []
    for j, k in enumerate((1, 2, 3, 5, 8)):
        rec = f"{i}table_audit.table.{j}."
        for col in ("cluster_coverage", "optimism"):
            for arm in ("original", "calibrated"):
                rows.append((f"{col.replace('_', ' ')} k={k}, {arm}", f"tab:audit.{col}_{arm}.{k}",
                             [f"{rec}{col}_{arm}", f"{rec}{col}_lo_{arm}", f"{rec}{col}_hi_{arm}"]))
    s = f"{i}table_audit.summary."
    rows += [("mean abs(coverage - nominal), original", "tab:audit.mean_abs_coverage_gap.original",
              f"{s}mean_abs_cluster_coverage_gap_original"),
             ("mean abs(coverage - nominal), calibrated", "tab:audit.mean_abs_coverage_gap.calibrated",
              f"{s}mean_abs_cluster_coverage_gap_calibrated"),
             ("mean abs(e_k), original", "tab:audit.mean_abs_optimism.original", f"{s}mean_abs_optimism_original"),
             ("mean abs(e_k), calibrated", "tab:audit.mean_abs_optimism.calibrated", f"{s}mean_abs_optimism_calibrated"),
             ("episode coverage k=1", "T11-audit-trend.coverage_k1", f"{i}text.episode_coverage_k1"),
             ("episode coverage k=8", "T11-audit-trend.coverage_k8", f"{i}text.episode_coverage_k8"),
             ("support escape k=1 (paper in %)", "T11-audit-trend.escape_k1", f"{i}text.escape_k1"),
             ("support escape k=8 (paper in %)", "T11-audit-trend.escape_k8", f"{i}text.escape_k8")]
    doc.table(_HEAD, _pair_rows(doc, rows))


def _table_v(doc: Doc, i: str) -> None:
    """Table V: the confirmation on untouched instances (Test C)."""
    doc.add("### Confirmation on untouched instances, Test C (Table V)", "")
    rows = []
    for row in ("escape_random_k8", "episode_coverage_random_k8", "optimism_random_k8", "failure_random_k8",
                "failure_cover_k5", "failure_cover_k1"):
        t = f"{i}table_testc.{row}."
        rows += [(f"{row}, old", f"tab:testc.{row}.old", f"{t}old"),
                 (f"{row}, corrected", f"tab:testc.{row}.corrected", f"{t}corrected"),
                 (f"{row}, old - corrected (paired)", f"tab:testc.{row}.diff", f"{t}old_minus_corrected")]
    t = f"{i}table_testc.failure_cover_k5_setcal_margin."
    rows += [("cover k=5 set+margin, old", "tab:testc.failure_cover_k5_setcal_margin.old", f"{t}old"),
             ("cover k=5 set+margin, corrected", "tab:testc.failure_cover_k5_setcal_margin.corrected", f"{t}corrected"),
             ("cover k=5 set+margin, old - corrected (paired)", "tab:testc.failure_cover_k5_setcal_margin.diff",
              f"{t}old_minus_corrected"),
             ("simultaneous threshold, corrected, cover", "T16-corrected-thresholds.cover",
              f"{t}simultaneous_threshold.corrected")]
    doc.table(_HEAD, _pair_rows(doc, rows))


def _table_viii(doc: Doc, i: str) -> None:
    """Table VIII: controlled mismatch tests, random k = 8."""
    doc.add("### Controlled mismatch tests, random k = 8 (Table VIII)", "")
    rows = []
    for fault in ("none", "noise", "boundary", "prior", "particles", "frame"):
        f = f"{i}table_faults.{fault}."
        rows += [(f"{fault}: failure", f"tab:faults.{fault}.fail", f"{f}fail"),
                 (f"{fault}: tempered T=4", f"tab:faults.{fault}.tempered", f"{f}tempered"),
                 (f"{fault}: known fix", f"tab:faults.{fault}.fix", f"{f}fix"),
                 (f"{fault}: fix - fault (paired)", f"T41-paired-fixes.{fault}", f"{f}paired_fix"),
                 (f"{fault}: surprise AUC", f"tab:faults.{fault}.surprise", f"{f}surprise_auc")]
    doc.table(_HEAD, [r for r in _pair_rows(doc, rows) if r[2] != DASH])


def _robust_filters(doc: Doc, i: str) -> None:
    """The robust filters under the boundary error."""
    doc.add("### Robust filters under the boundary error", "")
    r = f"{i}robust."
    rows = [(f"chosen {fam}", f"T42-robust-chosen.{fam}", f"{r}chosen.{fam}") for fam in ("tempering", "mixture",
                                                                                           "rejuvenation")]
    rows += [("escape, deployed", "T43-robust-filters.escape_deployed", f"{r}deployed.escape"),
             ("escape, mixture", "T43-robust-filters.escape_mixture", f"{r}mixture.escape"),
             ("escape, rejuvenation", "T43-robust-filters.escape_rejuvenation", f"{r}rejuvenation.escape"),
             ("failure change, mixture (paired)", "T43-robust-filters.mixture", f"{r}mixture.failure_diff"),
             ("failure change, rejuvenation (paired)", "T43-robust-filters.rejuvenation", f"{r}rejuvenation.failure_diff"),
             ("optimism, mixture", None, f"{r}mixture.optimism"),
             ("optimism, rejuvenation", None, f"{r}rejuvenation.optimism"),
             ("failure, right model", "T44-mixture-cost.right", f"{r}mixture_cost_when_right.0"),
             ("failure, right model + mixture", "T44-mixture-cost.mixture", f"{r}mixture_cost_when_right.1")]
    doc.table(_HEAD, _pair_rows(doc, rows))


def _resplits(doc: Doc, i: str) -> None:
    """Random re-splits of one pool (cover, k = 5)."""
    rs = f"{i}resplits."
    doc.add(f"### {doc.n(rs + 'splits', 'd')} random re-splits of one pool (cover, k = 5)", "")
    doc.table(_HEAD, _pair_rows(doc, [
        ("calibrated level, mean", "T14-resplits.level_mean", f"{rs}level_mean_sd.0"),
        ("calibrated level, SD", "T14-resplits.level_sd", f"{rs}level_mean_sd.1"),
        ("failure, mean", "T14-resplits.failure_mean", f"{rs}failure_mean_sd.0"),
        ("failure, SD", "T14-resplits.failure_sd", f"{rs}failure_mean_sd.1"),
        ("held-out cluster coverage", "T14-resplits.heldout_cluster_coverage", f"{rs}heldout_cluster_coverage"),
        ("margin optimistic (paper: % of splits)", "T14-resplits.margin_optimistic_percent",
         f"{rs}margin_optimistic_fraction")]))


def gates_table(doc: Doc, i: str) -> None:
    g = f"{i}gates.summary."
    rows = [["simultaneous threshold, cover (original)", doc.pv("T30-original-thresholds.cover"),
             doc.n(f"{i}table_insertion.simultaneous_cover")],
            ["simultaneous threshold, random (original)", doc.pv("T30-original-thresholds.random"),
             doc.n(f"{i}table_insertion.simultaneous_random")]]
    for j, record in enumerate(doc.value(f"{i}gates.summary")):
        sig = record["signal"]
        if f"T31-gate-areas.{sig}" in paper_values.PRINTED or sig == "oracle":
            rows.append([f"gate area, {sig}", doc.pv(f"T31-gate-areas.{sig}"), doc.n(f"{g}{j}.area")])
        if f"T33-committed-pool.{sig}.n_committed" in paper_values.PRINTED:
            p = f"T33-committed-pool.{sig}."
            rows.append([f"escaped in committed / rejected pool, {sig}",
                         f"{doc.pv(p + 'escaped_committed')}/{doc.pv(p + 'n_committed')} vs "
                         f"{doc.pv(p + 'escaped_rejected')}/{doc.pv(p + 'n_rejected')}",
                         f"{doc.n(f'{g}{j}.escaped_committed', 'd')}/{doc.n(f'{g}{j}.n_committed', 'd')} vs "
                         f"{doc.n(f'{g}{j}.escaped_rejected', 'd')}/{doc.n(f'{g}{j}.n_rejected', 'd')} "
                         f"(commit rate {doc.n(f'{g}{j}.commit_rate')})"])
        if f"T34-claimed-realized.{sig}_claimed" in paper_values.PRINTED:
            rows.append([f"claimed / realized at commit, {sig}",
                         f"{doc.pv(f'T34-claimed-realized.{sig}_claimed')} / {doc.pv(f'T34-claimed-realized.{sig}_realized')}",
                         f"{doc.n(f'{g}{j}.claimed')} / {doc.n(f'{g}{j}.realized')}"])
        if sig == "oracle":
            rows.append(["oracle: smallest commit rate at zero failure (paper in %)",
                         doc.pv("T35-oracle.commit_rate_percent"), doc.n(f"{g}{j}.c_min")])
    doc.add("### The commit decision, Split B, cover schedule (Sec. VI, Fig. 6)", "")
    doc.table(["quantity", "paper", "ours"], rows)


def breadth_section(doc: Doc) -> None:
    """Table II from breadth's results: Delta = Blind-Bayes - Probe-Robust(k) in every row."""
    if "breadth" not in doc.trees:
        return
    b = "breadth:results.table_II."
    doc.add("## Every family, blind against probed (Table II)", "",
            "Generated by `probecommit reproduce breadth` from `configs/paper/<family>.yaml` (insertion's row from "
            "`reproduce insertion`: failure on Split A, the cover schedule at k = 5). Mean miss with 95% cluster-bootstrap "
            "intervals (m; rad for the hinge; success on the feasible subset for grasp); Probe-Robust at k = 5, two for "
            "shuffleboard, eight for grasp. Delta is the paper's: Blind-Bayes - Probe-Robust(k), paired on identical "
            "episodes, cluster bootstrap, in every row (for grasp, the gain in success); Blind-Robust - Probe-Robust(k) "
            "(only the information changes) is the extra column. Our priors, truth sets, targets and scenes are our own "
            "(`docs/families.md`).", "")
    rows = []
    for family in doc.trees["breadth"]["results"].get("table_II", {}):
        r, p = f"{b}{family}.", f"tab:breadth.{family}."
        rows.append([f"{family} (ours)", doc.ci([f"{r}blind_bayes", f"{r}blind_bayes_lo", f"{r}blind_bayes_hi"]),
                     doc.ci([f"{r}blind_robust", f"{r}blind_robust_lo", f"{r}blind_robust_hi"]),
                     doc.ci([f"{r}probe_robust", f"{r}probe_robust_lo", f"{r}probe_robust_hi"]),
                     doc.ci([f"{r}paired", f"{r}paired_lo", f"{r}paired_hi"]),
                     doc.ci([f"{r}paired_robust", f"{r}paired_robust_lo", f"{r}paired_robust_hi"])])
        delta = (f"{doc.pv(p + 'delta')} [{doc.pv(p + 'delta_lo')}, {doc.pv(p + 'delta_hi')}]"
                 if p + "delta" in paper_values.PRINTED else doc.pv(p + "change_percent"))
        rows.append([f"{family} (paper)", doc.pv(p + "blind_bayes"), doc.pv(p + "blind_robust"),
                     doc.pv(p + "probe_robust"), delta + (" %" if p + "change_percent" in paper_values.PRINTED else ""),
                     DASH])
    doc.table(["family", "Blind-Bayes", "Blind-Robust", "Probe-Robust(k)", "Delta = Blind-Bayes - Probe-Robust [95%]",
               "Blind-Robust - Probe-Robust [95%]"], rows)
    flips = doc.trees["breadth"]["results"].get("sign_flip_over_truths", {})
    for family in flips:
        f = f"breadth:results.sign_flip_over_truths.{family}."
        doc.add(f"{family}: {doc.n(f + 'n_feasible', 'd')} of {doc.n(f + 'n_instances', 'd')} truths are feasible. Per "
                f"feasible truth, Probe-Robust(8) minus Blind-Bayes success: {doc.n(f + 'n_improve', 'd')} improve (by "
                f"{doc.n(f + 'improve_min', '.2f')} to {doc.n(f + 'improve_max', '.2f')}), {doc.n(f + 'n_tie', 'd')} tie, "
                f"{doc.n(f + 'n_worse', 'd')} worsen; exact sign-flip test over truths p = {doc.n(f + 'p_sign_flip', '.4f')} "
                f"(paper: {doc.pv('T09-grasp.improve')} improve by {doc.pv('T09-grasp.improve_min')} to "
                f"{doc.pv('T09-grasp.improve_max')}, p cannot fall below {doc.pv('T09-grasp.p')}).", "")


def cost_section(doc: Doc) -> None:
    if "cost" not in doc.trees:
        return
    doc.add("## Probe pricing (paper Sec. III, \"Probe protocol and cost\")", "",
            "Generated by `probecommit reproduce cost` from the frozen breadth curves: J(k) = miss(k) + lambda k for "
            "Blind-Robust (k = 0) and Probe-Robust (k = 2, 5). Above 'blind above' a blind commit beats every budget; "
            "below 'five below' five probes are optimal. Ours in m (rad for the hinge) per probe; the paper's in cm "
            "(rad for the hinge).", "")
    rows = []
    for family in doc.trees["cost"]["results"].get("prices", {}):
        c = f"cost:results.prices.{family}."
        rows.append([family, doc.n(c + "miss_0"), doc.n(c + "miss_2"), doc.n(c + "miss_5"), doc.n(c + "blind_above", ".4f"),
                     doc.n(c + "five_below", ".4f"), doc.pv(f"T01-pricing.blind_above.{family}"),
                     doc.pv(f"T01-pricing.five_below.{family}")])
    doc.table(["family", "miss(0)", "miss(2)", "miss(5)", "blind above (ours)", "five below (ours)",
               "paper: blind above", "paper: five below"], rows)


def gru_section(doc: Doc) -> None:
    if "gru" not in doc.trees:
        return
    g = "gru:results."
    doc.add("## The learned baseline (GRU on MuJoCo 2-D pushing)", "",
            "Generated by `probecommit reproduce gru` from `configs/paper/gru.yaml` (margin fixed before the seeds ran): "
            "a GRU reading the pipeline's stored probe histories and targets, trained on expected miss, its impulse "
            "snapped to the pipeline's action grid, scored in MuJoCo on the same episodes.", "")
    doc.table(["quantity", "paper", "ours [95% CI]"], [
        ["pipeline mean miss, Probe-Robust(5) (m)", doc.pv("T10-gru.pipeline"), doc.n(g + "pipeline_miss")],
        ["GRU mean miss over the seeds (m)", doc.pv("T10-gru.gru"), doc.n(g + "gru_miss")],
        ["GRU - pipeline (m)", f"{doc.pv('T10-gru.diff')} [{doc.pv('T10-gru.diff_lo')}, {doc.pv('T10-gru.diff_hi')}]",
         doc.ci(g + "gru_minus_pipeline", "+.3f")],
        ["equivalence margin (m)", doc.pv("T10-gru.margin"), doc.n(g + "equivalence_margin")],
        ["seeds", DASH, doc.n(g + "seeds", "d")]])


def engines_section(doc: Doc) -> None:
    if "engines" not in doc.trees:
        return
    e = "engines:results."
    res = doc.trees["engines"]["results"]
    doc.add("## Across engines (Table VI; PyBullet and PhysX)", "",
            "Generated by `probecommit reproduce engines`: the MuJoCo insertion scene rebuilt from the same dimensions, "
            "masses and drives in PyBullet and SAPIEN/PhysX (settings chosen for numerical soundness at millimetre "
            "scale, never tuned toward a number; `docs/decisions.md`), the same belief, protocol and audit. Random probes "
            "on the Split B test instances, k = 8.", "")
    rows = []
    for engine in res.get("scans", {}):
        s = f"{e}scans.{engine}."
        rows.append([engine, doc.n(s + "boundary.delta", "+.3f"), doc.pv(f"T18-engine-scans.{engine}_offset"),
                     doc.n(s + "capture.ratio_mean"), doc.n(s + "capture.ratio_sd"),
                     doc.pv(f"T18-engine-scans.{engine}_ratio")])
    doc.table(["engine", "boundary offset (mm, hg + delta)", "paper", "capture window / w(c)", "SD over truths",
               "paper"], rows)
    rows = []
    for column in res.get("table", {}):
        for metric in ("support_escape", "episode_coverage", "optimism_e_k", "failure"):
            rows.append([f"{column}: {metric}", doc.pv(f"tab:engines.{column}.{metric}"),
                         doc.n(f"{e}table.{column}.{metric}", "+.3f" if metric.startswith("optimism") else ".3f")])
    doc.table(["engine/variant: quantity", "paper", "ours"], rows)
    rows = []
    for column in res.get("paired", {}):
        claim = "T20-pybullet-transfer" if column.startswith("pybullet") else "T22-physx-paired"
        variant = column.split("/")[1]
        rows.append([column, doc.pv(f"{claim}.{variant}"), doc.ci(f"{e}paired.{column}", "+.3f")])
    doc.add("Paired failure difference at k = 8 against the deployed model (cluster bootstrap):", "")
    doc.table(["engine/variant", "paper", "ours [95% CI]"], rows)
    rows = []
    for column, by_k in res.get("escape", {}).items():
        rows.append([column] + [doc.n(f"{e}escape.{column}.{k}") for k in by_k])
    if rows:
        ks = list(next(iter(res["escape"].values())))
        doc.add(f"Support escape against the budget (paper, PyBullet deployed: {doc.pv('T19-pybullet-escape.k1')} at "
                f"k = 1 to {doc.pv('T19-pybullet-escape.k8')} at k = 8):", "")
        doc.table(["engine/variant"] + [f"k={k}" for k in ks], rows)


def robot_section(doc: Doc) -> None:
    """Table VII and Fig. 5b-d on the simulated rig, every artifact labelled so."""
    if "robot" not in doc.trees:
        return
    r = "robot:results."
    res = doc.trees["robot"]["results"]
    doc.add("## The robot run (paper Sec. V-D, Table VII, Fig. 5) -- on the simulated rig", "",
            f"Generated by `probecommit reproduce robot` from `configs/paper/rig.yaml`. **We have no arm**: every number "
            f"in this section comes from the simulated rig ({res.get('engine', '?')} engine, touch-switch "
            "descent at the paper's rig scale) driving the same `probecommit.Session` a physical rig uses, so its log "
            "goes through exactly the audit and replay a real log does. The paper's values are the physical arm's and "
            "sit only in columns labelled so; they are not expected to match.", "")
    doc.add(f"{doc.n(r + 'episodes', 'd')} simulated-rig episodes at {doc.n(r + 'positions', 'd')} positions; covered "
            f"on {doc.n(r + 'n_covered', 'd')}, support escape on {doc.n(r + 'n_escaped', 'd')}; replayed as deployed "
            f"the log reproduces {doc.n(r + 'replay_reproduced_fraction')} of its recorded decisions.", "")
    rows = []
    for j, row in enumerate(res.get("table", [])):
        t = f"{r}table.{j}."
        taps = row["taps"]
        paper = " / ".join(doc.pv(f"tab:hardware.{taps}.{c}") for c in ("episodes", "entered", "predicted", "realized",
                                                                          "optimism"))
        rows.append([doc.n(t + "taps", "d"), doc.n(t + "episodes", "d"), doc.n(t + "entered", "d"),
                     doc.n(t + "predicted"), doc.n(t + "realized"),
                     doc.ci([t + "optimism", t + "optimism_lo", t + "optimism_hi"], "+.3f"),
                     doc.ci([t + "aim_error", t + "aim_error_lo", t + "aim_error_hi"], ".1f"), paper])
    doc.table(["taps", "episodes (sim. rig)", "entered (sim. rig)", "predicted (sim. rig)", "realized (sim. rig)",
               "optimism [95% CI] (sim. rig)", "aim error mm [95% CI] (sim. rig)",
               "paper, physical arm: episodes / entered / predicted / realized / optimism"], rows)
    excluding = [j for j, row in enumerate(res.get("table", []))
                 if row.get("optimism_lo", 0) > 0 or row.get("optimism_hi", 0) < 0]
    if excluding:
        parts = [f"{doc.n(f'{r}table.{j}.taps', 'd')} taps ({doc.ci([f'{r}table.{j}.optimism', f'{r}table.{j}.optimism_lo', f'{r}table.{j}.optimism_hi'], '+.3f')})"
                 for j in excluding]
        doc.add("On the simulated rig the optimism interval excludes zero at " + " and at ".join(parts) + ". "
                + (f"Pooled over every budget the optimism is {doc.n(r + 'optimism_pooled', '+.3f')}: "
                   if doc.has(r + "optimism_pooled") else "")
                + f"each interval rests on {doc.n(r + 'positions', 'd')} positions, and with several budgets each "
                "tested at 95 % an interval excluding zero in either direction is expected now and then; the paper's "
                "claim that every interval covers zero does not reproduce on this rig.", "")
    first = f"{r}boundary_first_resolved_mm"
    doc.add("### Recorded taps under a boundary pulled inward (Fig. 5c, simulated rig)", "",
            (f"Optimism of the faulted model minus the deployed one, paired over positions; first resolved at "
             f"{doc.n(first, 'g')} mm (paper, physical arm: {doc.pv('T28-replay-boundary.first_mm')} mm); no coverage "
             f"change resolved up to {doc.n(r + 'boundary_holds_to_mm', 'g')} mm (paper: "
             f"{doc.pv('T28-replay-boundary.coverage_holds_mm')} mm).") if doc.has(first)
            else "No boundary fault size resolves the optimism condition on this log.", "")
    _sweep(doc, "boundary_by_mm", "boundary pulled in (mm)")
    doc.add("### Recorded taps under a narrowed prior (Fig. 5d, simulated rig)", "")
    p = f"{r}prior_by_mm.12."
    if doc.has(p + "coverage"):
        doc.add(f"At +-12 mm: coverage {doc.n(p + 'coverage')}, support escape {doc.n(p + 'escape')}, optimism "
                f"{doc.n(p + 'optimism', '+.3f')} (paper, physical arm: {doc.pv('T29-replay-prior.coverage')}, "
                f"{doc.pv('T29-replay-prior.escape')}, {doc.pv('T29-replay-prior.optimism')}).", "")
    _sweep(doc, "prior_by_mm", "prior half-width (mm)")


def _sweep(doc: Doc, name: str, label: str) -> None:
    rows = []
    for size in doc.trees["robot"]["results"].get(name, {}):
        s = f"robot:results.{name}.{size}."
        rows.append([doc.n(s + "size", "g"), doc.n(s + "coverage"), doc.n(s + "escape"), doc.n(s + "optimism", "+.3f"),
                     doc.ci([s + "delta_optimism", s + "delta_optimism_lo", s + "delta_optimism_hi"], "+.3f"),
                     doc.ci([s + "delta_coverage", s + "delta_coverage_lo", s + "delta_coverage_hi"], "+.3f")])
    doc.table([f"{label} (sim. rig)", "coverage", "escape", "optimism", "d optimism [95% CI]", "d coverage [95% CI]"],
              rows)


def beyond_section(doc: Doc) -> None:
    if "beyond" not in doc.trees:
        return
    b = "beyond:results."
    res = doc.trees["beyond"]["results"]
    doc.add("## Beyond the paper (options; the paper's behaviour stays the default)", "",
            "Generated by `probecommit reproduce beyond` from the insertion reproduction's MuJoCo run directories (and "
            "the push1d run). See `docs/beyond-the-paper.md` for what each option is.", "",
            "### Set at t = 1: prefix (paper) vs hull, calibrated on Split B cal, tested on Split B test (random probes)",
            "")
    plateau = res.get("plateau", [])
    rows = []
    for k in sorted({row["k"] for row in plateau}):
        pre = next(j for j, row in enumerate(plateau) if row["k"] == k and row["plateau"] == "prefix")
        hull = next(j for j, row in enumerate(plateau) if row["k"] == k and row["plateau"] == "hull")
        rows.append([doc.n(f"{b}plateau.{pre}.k", "d"), doc.n(f"{b}plateau.{pre}.threshold"),
                     doc.n(f"{b}plateau.{pre}.cluster_coverage_calibrated"),
                     doc.n(f"{b}plateau.{hull}.cluster_coverage_calibrated")])
    doc.table(["k", "threshold", "cluster coverage, prefix", "cluster coverage, hull"], rows)
    doc.add("### Belief move: the paper's jitter vs resample-move (MH), random probes, k = 8", "")
    doc.table(["run", "move", "escape", "episode coverage", "optimism", "failure"], [
        [row["run"], row["move"], doc.n(f"{b}moves.{j}.escape"), doc.n(f"{b}moves.{j}.episode_coverage"),
         doc.n(f"{b}moves.{j}.optimism", "+.3f"), doc.n(f"{b}moves.{j}.failure")]
        for j, row in enumerate(res.get("moves", []))])
    doc.add("### Probe selection: random, the cover schedule and adaptive probes (realized = failure for insertion, "
            "miss in m for push1d)", "")
    doc.table(["run", "schedule", "k", "realized", "predicted", "optimism", "episode coverage", "escape"], [
        [row["run"], row["schedule"], doc.n(f"{b}adaptive.{j}.k", "d"), doc.n(f"{b}adaptive.{j}.realized"),
         doc.n(f"{b}adaptive.{j}.predicted"), doc.n(f"{b}adaptive.{j}.optimism", "+.3f"),
         doc.n(f"{b}adaptive.{j}.episode_coverage"), doc.n(f"{b}adaptive.{j}.escape")]
        for j, row in enumerate(res.get("adaptive", []))])
