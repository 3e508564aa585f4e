"""``probecommit verify``: every published number must follow from the stored data.

A publication (``results/paper`` in a checkout, or a ``--publish-to`` folder's
``results/paper``) holds one folder per study, the root files (``reproduction.json``,
``report.html``) and REPRODUCTION.md two levels up. The verifier reads files only and checks,
by kind:

* **recomputed**: each study's summary numbers recomputed from its stored episode-level
  tables with the stored bootstrap seeds (``report.recompute``) and compared with
  ``results.json``; derived Parquet tables (fault signatures, Table II, budget curves, prices)
  rebuilt and compared cell by cell; figures' data digests compared with their data;
* **traced**: every published text file rendered again from the stored data
  (``report.rerender``: each table from its study's results, each ``.tex`` from its ``.md``,
  claims.json (the claims' statuses recomputed from the registry), REPRODUCTION.md, the
  published-numbers ledger and report.html from the whole publication) and compared; a
  difference names the file, the line and the number (for claims.json, the claim whose status
  differs); every ledger entry re-resolved and re-formatted, and every number in a ledgered
  file accounted for (``report.ledger``);
* **identities** and **ranges**: intervals contain their points, paired differences equal
  their rows', a results.json table equals its Parquet twin, rates in [0, 1], no NaN or inf
  unless declared (``report.checks``);
* **files**: the publication and study manifests exist, list every file the folders hold,
  and match their bytes; REPRODUCTION.md exists.

The headline is the number of distinct published numbers verified (recomputed, or printed in
a file that re-renders identically); traced-only numbers are counted apart.
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
from probecommit.store.manifest_rules import ManifestError, read_json, read_manifest
from probecommit.store.safefile import write_text

from probecommit.report import checks, manifest
from probecommit.report.manifest import MANIFEST, REPRODUCTION_REL, write_manifest  # noqa: F401 (re-exported)

#: Publishing writes ``published_numbers.json`` (REPRODUCTION.md's numbers and their keys): a missing ledger fails.
REQUIRE_LEDGER = True
TOLERANCE = 1e-9
_NUMBER = re.compile(r"(?<![\w.])[+-]?(?:\d+\.\d+|\d+)(?:e[+-]?\d+)?")
#: A results.json list of records and the Parquet table it mirrors, per study.
#: A dict of records (keyed by a row's name, ``table_II.push1d``) is compared in the table's row order.
TWINS = {"breadth": {"table_II": "table_II_breadth.parquet", "curves": "budget_curves.parquet"},
         "cost": {"pricing": "pricing.parquet", "prices": "pricing.parquet"},
         "robot": {"table": "table_robot.parquet", "boundary_fault": "fault_boundary.parquet",
                   "prior_fault": "fault_prior.parquet", "boundary_by_mm": "fault_boundary.parquet",
                   "prior_by_mm": "fault_prior.parquet"},
         "engines": {"escape_by_budget": "escape_by_budget.parquet"},
         "beyond": {"plateau": "plateau.parquet", "moves": "moves.parquet", "adaptive": "adaptive.parquet"}}


@dataclass
class Report:
    """Checks by kind, failures one line each, and the published numbers they verified."""

    counts: Counter = field(default_factory=Counter)
    failures: list[str] = field(default_factory=list)
    verified_numbers: int = 0
    traced_only_numbers: int = 0
    #: Traced-only results.json numbers by why they are not recomputed (``recompute.TRACED_KINDS``).
    traced_only_kinds: Counter = field(default_factory=Counter)
    notes: list[str] = field(default_factory=list)

    def check(self, kind: str, ok: bool, message: str) -> None:
        self.counts[kind] += 1
        if not ok:
            self.failures.append(message)

    @property
    def checked(self) -> int:
        return sum(self.counts.values())

    @property
    def ok(self) -> bool:
        return not self.failures

    def summary(self) -> str:
        kinds = ", ".join(f"{self.counts[k]} {k}" for k in ("recomputed", "traced", "identity", "range", "file")
                          if self.counts[k])
        why = ", ".join(f"{n} {kind}" for kind, n in sorted(self.traced_only_kinds.items(), key=lambda kv: -kv[1]))
        return (f"{self.verified_numbers} published numbers verified ({kinds} checks); "
                f"{self.traced_only_numbers} results.json numbers traced only{f' ({why})' if why else ''}; "
                f"{len(self.failures)} failed")


# ----------------------------------------------------------------------------- layout


def publication_root(path: str | Path) -> Path:
    """The publication root under ``path``: itself, ``paper/``, or ``results/paper/``."""
    path = Path(path)
    for candidate in (path, path / "paper", path / "results" / "paper"):
        if (candidate / MANIFEST).is_file() and "studies" in _json(candidate / MANIFEST, {}):
            return candidate
        if candidate.is_dir() and any((p / "results.json").is_file() for p in candidate.iterdir() if p.is_dir()):
            return candidate
    raise FileNotFoundError(f"{path} holds no publication (results/paper with study folders and {MANIFEST})")


def _json(path: Path, default: Any = None) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return default


def _read(path: Path, report: Report, what: str, manifest_file: bool = False) -> Any:
    """A manifest or results file under the store's rule set; a malformed one is one failure naming it
    (the file, the field or the line), never a traceback. None when missing or malformed."""
    if not path.is_file():
        return None
    try:
        return read_manifest(path) if manifest_file else read_json(path, what)
    except ManifestError as exc:
        report.check("file", False, str(exc))
        return None


def check_root(root: Path, report: Report) -> list[Path]:
    """The publication manifest: present, listing every root file and study, bytes matching."""
    path = root / MANIFEST
    report.check("file", path.is_file(), f"{path}: no publication manifest")
    report.check("file", (root / REPRODUCTION_REL).is_file(),
                 f"{(root / REPRODUCTION_REL).resolve()}: no REPRODUCTION.md beside the publication")
    studies = sorted(p for p in root.iterdir() if p.is_dir())
    # read as JSON, not under the study-manifest rules: it names REPRODUCTION.md two levels up on purpose
    listed = _read(path, report, "publication manifest") or {}
    if not isinstance(listed, dict) or not isinstance(listed.get("sha256", {}), dict):
        report.check("file", False, f"{path}: field 'sha256' must map each file to its digest")
        listed = {}
    _hashes(root, listed.get("sha256", {}), manifest.root_files(root), report)
    named = set(listed.get("studies", []))
    for name in sorted(named ^ {p.name for p in studies}):
        state = "listed in" if name in named else "not in"
        report.check("file", False, f"{root / name}: study folder {state} {MANIFEST}{' but missing' if name in named else ''}")
    return studies


def _hashes(folder: Path, listed: dict[str, str], present: list[str], report: Report) -> None:
    for name, digest in sorted(listed.items()):
        target = folder / name
        if not target.is_file():
            report.check("file", False, f"{target}: listed in {MANIFEST} but missing")
        else:
            report.check("file", manifest.sha256_file(target) == digest, f"{target}: sha256 differs from {MANIFEST}")
    for name in present:
        report.check("file", name in listed, f"{folder / name}: a file not in {MANIFEST}")


def check_study_files(study: Path, report: Report) -> None:
    """The study manifest, and each figure bound to the digest of the data it was drawn from."""
    path = study / MANIFEST
    report.check("file", path.is_file(), f"{path}: no study manifest")
    listed = _read(path, report, "study manifest", manifest_file=True) or {}
    _hashes(study, listed.get("sha256", {}), manifest.study_files(study), report)
    for sub in sorted(p for p in study.iterdir() if p.is_dir()):
        report.check("file", False, f"{sub}: a folder inside a study folder (a publication holds files only)")
    for png in sorted(study.glob("fig_*.png")):  # a paper figure is published as PNG and PDF
        report.check("file", png.with_suffix(".pdf").is_file(), f"{png}: a figure without its PDF beside it")
    for fig in sorted(study.glob("*.png")):
        binding = listed.get("figures", {}).get(fig.name)
        declared = manifest.FIGURE_DATA.get(study.name, {}).get(fig.stem, ())
        if not declared:
            if fig.stem not in manifest.CODE_FIGURES.get(study.name, ()):
                report.notes.append(f"{study.name}/{fig.name}: drawn from run directories the publication does not hold")
            continue
        ok = binding is not None and binding.get("data") == list(declared)
        report.check("file", ok, f"{fig}: manifest does not bind it to its data {list(declared)}")
        if not ok or not all((study / n).is_file() for n in declared):
            continue
        digest = manifest.data_digest(study, declared)
        report.check("recomputed", binding.get("data_sha256") == digest,
                     f"{fig}: drawn from data with digest {str(binding.get('data_sha256'))[:12]}, its data "
                     f"{', '.join(declared)} now digest {digest[:12]}")
        carried = manifest.png_data_digest(fig)
        report.check("recomputed", carried == digest,
                     f"{fig}: the figure carries data digest {str(carried)[:12]}, not its data's {digest[:12]} "
                     "(drawn from other data)")


# ----------------------------------------------------------------------------- numbers


def _count_numbers(text: str) -> int:
    return len(_NUMBER.findall(text))


def _equal(a: Any, b: Any) -> bool:
    if checks.is_number(a) and checks.is_number(b):
        if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
            return True
        return abs(float(a) - float(b)) <= TOLERANCE * max(1.0, abs(float(b)))
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if a is None and isinstance(b, float) and math.isnan(b):
        return True
    return a == b


def _first_difference(key: str, published: Any, expected: Any) -> tuple[str, Any, Any]:
    """The dotted key of the first leaf where two values differ (a table of values names its one cell)."""
    if isinstance(published, dict) and isinstance(expected, dict) and published.keys() == expected.keys():
        part = next(k for k in expected if not _equal(published[k], expected[k]))
        return _first_difference(f"{key}.{part}", published[part], expected[part])
    if isinstance(published, list) and isinstance(expected, list) and len(published) == len(expected):
        i = next(i for i, (x, y) in enumerate(zip(published, expected)) if not _equal(x, y))
        return _first_difference(f"{key}.{i}", published[i], expected[i])
    return key, published, expected


def _leaves(value: Any) -> int:
    return sum(1 for _, v in checks.walk(value) if checks.is_number(v))


def check_recomputed(study: Path, results: dict[str, Any], report: Report) -> set[str]:
    """Recompute the study's numbers from its episode tables; return the keys recomputed (a results.json
    copy of a rebuilt Parquet table, ``TWINS``, counts as recomputed: ``check_twins`` compares the two)."""
    from probecommit.report.ledger import walk_dotted
    from probecommit.report.recompute import STORED_TABLES, STUDIES

    for name in STORED_TABLES.get(study.name, ()):
        report.check("file", (study / name).is_file(),
                     f"{study.name}/{name}: missing (the stored rows the study's numbers are recomputed from)")
    if study.name not in STUDIES:
        return set()
    try:
        again = STUDIES[study.name](study, results)
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:
        report.check("recomputed", False, f"{study}: cannot recompute from the stored tables ({type(exc).__name__}: {exc})")
        return set()
    for key, value in again.values.items():
        try:
            published = walk_dotted(results, key.split("."))
        except KeyError:
            report.check("recomputed", False, f"{study.name}/results.json: {key} missing (the stored episodes give {value})")
            continue
        report.counts["recomputed"] += _leaves(value) - 1
        ok = _equal(published, value)
        where, a, b = (key, published, value) if ok else _first_difference(key, published, value)
        report.check("recomputed", ok, f"{study.name}/results.json: {where} = {a} but {again.source(key)} gives {b}")
    for name, table in again.tables.items():
        _compare_table(study, name, table, again.table_sources.get(name, "the stored episode tables"), report)
    for ok, message in again.consistency:
        report.check("recomputed", ok, message)
    twins = {key for key, name in TWINS.get(study.name, {}).items() if name in again.tables and key in results}
    return set(again.values) | twins


def _compare_table(study: Path, name: str, expected: pd.DataFrame, source: str, report: Report) -> None:
    path = study / name
    if not path.is_file():
        report.check("recomputed", False, f"{path}: missing (it is derived from the stored episodes)")
        return
    stored = pd.read_parquet(path).reset_index(drop=True)
    expected = expected.reset_index(drop=True)
    if list(stored.columns) != list(expected.columns) or len(stored) != len(expected):
        report.check("recomputed", False, f"{study.name}/{name}: {len(stored)} rows x {list(stored.columns)}, {source} "
                                          f"gives {len(expected)} rows x {list(expected.columns)}")
        return
    for column in stored.columns:
        for row, (a, b) in enumerate(zip(stored[column].tolist(), expected[column].tolist())):
            report.counts["recomputed"] += 1
            if not _equal(a, b):
                report.check("recomputed", False, f"{study.name}/{name}: row {row} {column} = {a}, {source} gives {b}")
                break


def check_twins(study: Path, results: dict[str, Any], report: Report) -> None:
    """A results.json list of records equals the Parquet table it was written with."""
    for key, name in TWINS.get(study.name, {}).items():
        if key not in results or not (study / name).is_file():
            continue
        table = pd.read_parquet(study / name).reset_index(drop=True)
        by_name = isinstance(results[key], dict)
        records = list(results[key].values()) if by_name else results[key]
        labels = list(results[key]) if by_name else list(range(len(records)))
        report.check("identity", len(records) == len(table),
                     f"{study.name}/results.json: {key} has {len(records)} rows, {name} has {len(table)}")
        for i, rec, row in zip(labels, records, table.to_dict("records")):
            bad = [c for c in rec if c in row and not _equal(_plain(rec[c]), _plain(row[c]))]
            report.check("identity", not bad, f"{study.name}/results.json: {key}.{i}.{bad[0] if bad else ''} = "
                                              f"{rec.get(bad[0]) if bad else ''} but {name} holds "
                                              f"{row.get(bad[0]) if bad else ''}")


#: A results.json dict of records by name and the list it copies (study -> (by name, list, name field)).
JSON_TWINS = {"setup": [("families_by_name", "families", "family")]}


def check_json_twins(study: Path, results: dict[str, Any], report: Report) -> None:
    """A by-name copy in results.json equals the list of records it was made from."""
    for by_name, listed, field_ in JSON_TWINS.get(study.name, []):
        if by_name not in results or listed not in results:
            continue
        expected = {r[field_]: r for r in results[listed]}
        ok = _equal(results[by_name], expected)
        where, a, b = (by_name, None, None) if ok else _first_difference(by_name, results[by_name], expected)
        report.check("identity", ok, f"{study.name}/results.json: {where} = {a} but {listed} holds {b}")


def _plain(v: Any) -> Any:
    if hasattr(v, "tolist"):
        v = v.tolist()
    return v


def check_texts(study: Path, report: Report) -> None:
    """Every table of the study rendered again from the stored data, compared with the published file."""
    from probecommit.report.rerender import expected_texts, first_difference, study_texts

    try:
        texts = study_texts(study)
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:
        report.check("traced", False, f"{study}: cannot render its tables from the stored data ({type(exc).__name__}: {exc})")
        return
    for name in expected_texts(study.name):
        report.check("file", (study / name).is_file(), f"{study.name}/{name}: missing (the study publishes it)")
    for name in sorted(p.name for p in study.iterdir() if p.suffix in (".md", ".tex")):
        if name not in texts:
            report.notes.append(f"{study.name}/{name}: not rendered again (traced by its hash only)")
            continue
        published = (study / name).read_text()
        ok = published == texts[name]
        report.check("traced", ok, f"{study.name}/{name}: {first_difference(published, texts[name])}")
        if ok:
            report.verified_numbers += _count_numbers(published)


def check_figures(study: Path, report: Report) -> None:
    """Each figure that can be drawn from the stored data, drawn again: its PDF and PNG must be those bytes."""
    from probecommit.report.manifest import strip_stamp
    from probecommit.report.rerender import study_figures

    try:
        drawn = study_figures(study)
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:
        report.check("recomputed", False, f"{study}: cannot draw its figures from the stored data ({type(exc).__name__}: {exc})")
        return
    for name, expected in sorted(drawn.items()):
        published = (study / name).read_bytes()
        if name.endswith(".png"):
            published = strip_stamp(published)
        report.check("recomputed", published == expected,
                     f"{study.name}/{name}: not the figure its stored data draw (drawn again, the bytes differ)")


def check_publication_texts(root: Path, report: Report) -> None:
    """REPRODUCTION.md and report.html rendered again from the whole publication."""
    from probecommit.report.rerender import first_difference, publication_texts

    if not (root / REPRODUCTION_REL).is_file():
        return
    try:
        texts = publication_texts(root)
    except (OSError, KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
        report.check("traced", False,
                     f"REPRODUCTION.md: cannot render it from the publication ({type(exc).__name__}: {exc})")
        return
    for rel, expected in texts.items():
        path = root / rel
        name = Path(rel).name
        if not path.is_file():
            report.check("file", False, f"{name}: missing (publishing writes it)")
            continue
        published = path.read_bytes()
        ok = published == expected
        where = first_difference(published.decode(errors="replace"), expected.decode(errors="replace"))
        if not ok and name == "claims.json":
            where = _claims_difference(published, expected) or where
        report.check("traced", ok, f"{name}: {where} (rendered from the studies' results, tables and reproduction.json)")
        if ok and name.endswith(".md"):
            report.verified_numbers += _count_numbers(published.decode())


def _claims_difference(published: bytes, expected: bytes) -> str | None:
    """The first claim whose status (or the counts) claims.json holds but the registry does not recompute."""
    try:
        stored, again = json.loads(published.decode(errors="replace")), json.loads(expected)
    except ValueError:
        return "not JSON"
    if stored.get("counts") != again.get("counts"):
        return f"counts {stored.get('counts')} but the registry recomputes {again.get('counts')}"
    for cid, entry in again.get("claims", {}).items():
        old = stored.get("claims", {}).get(cid, {})
        if (old.get("status"), old.get("experiment")) != (entry["status"], entry["experiment"]):
            return f"{cid} is {old.get('status')!r} but recomputes as {entry['status']!r}"
    return None


def check_ledger(root: Path, report: Report) -> None:
    """The published-numbers ledger, where publishing wrote one: every key re-resolved and found."""
    from probecommit.report import ledger
    from probecommit.studies.paper_values import tree

    if not (root / ledger.LEDGER_NAME).is_file():
        report.check("file", not REQUIRE_LEDGER, f"{root / ledger.LEDGER_NAME}: no published-numbers ledger")
        return
    try:
        entries = ledger.read(root)
    except (ValueError, TypeError, KeyError) as exc:
        report.check("traced", False, f"{ledger.LEDGER_NAME}: {exc}")
        return
    problems = list(ledger.check(entries, root, extra={"paper": tree()})) + list(ledger.uncovered(entries, root))
    report.counts["traced"] += max(len(entries) - len(problems), 0)
    for problem in problems:
        report.check("traced", False, problem)


# ----------------------------------------------------------------------------- entry point


def verify(results_root: str | Path, reproduction_md: str | Path | None = None, *, figures: bool = True) -> Report:
    """Verify a publication (``results/``, ``results/paper`` or a ``--publish-to`` folder).

    Args:
        results_root: Where the publication is.
        reproduction_md: Unused (REPRODUCTION.md sits two levels above the publication root);
            kept for callers of the earlier signature.
        figures: Draw the figures again from the stored data and compare their bytes (a few
            seconds a figure). Off, a figure is still checked against its data's digest.

    Returns:
        The report: checks by kind, failures, and the count of published numbers verified.
    """
    root = publication_root(results_root)
    report = Report()
    for study in check_root(root, report):
        check_study_files(study, report)
        payload = _read(study / "results.json", report, "results file")
        report.check("file", (study / "results.json").is_file(), f"{study}/results.json: missing")
        if not isinstance(payload, dict):
            continue
        results = payload.get("results", {})
        checks.nonfinite(study.name, "results.json", payload, report)
        checks.json_invariants(study.name, payload, report)
        for path in sorted(study.glob("*.parquet")):
            try:
                frame = pd.read_parquet(path)
            except Exception as exc:  # noqa: BLE001 - an unreadable table is one failed check
                report.check("file", False, f"{path}: unreadable ({type(exc).__name__})")
                continue
            checks.parquet_invariants(study.name, path.name, frame, report)
        keys = check_recomputed(study, results, report)
        report.verified_numbers += sum(_leaves(_get(results, k)) for k in keys)
        _count_traced(study.name, results, keys, report)
        check_twins(study, results, report)
        check_json_twins(study, results, report)
        check_texts(study, report)
        if figures:
            check_figures(study, report)
    check_publication_texts(root, report)
    check_ledger(root, report)
    return report


def _count_traced(study: str, results: dict[str, Any], recomputed: set[str], report: Report) -> None:
    """Count each results.json number no recomputed key covers by why it is traced only (``recompute.traced_kind``),
    and note each study's traced keys by kind (``verify --notes``)."""
    from probecommit.report.recompute import traced_kind

    by_kind: dict[str, list[str]] = {}
    for path, value in checks.walk(results):
        if not checks.is_number(value):
            continue
        parts = path.split(".")
        if any(".".join(parts[:n]) in recomputed for n in range(1, len(parts) + 1)):
            continue
        by_kind.setdefault(traced_kind(study, path), []).append(path)
    for kind, paths in by_kind.items():
        report.traced_only_numbers += len(paths)
        report.traced_only_kinds[kind] += len(paths)
        groups = sorted({".".join(p.split(".")[:2]) for p in paths})
        report.notes.append(f"{study}/results.json: {len(paths)} numbers, {kind}: {', '.join(groups[:12])}"
                            f"{f' and {len(groups) - 12} more' if len(groups) > 12 else ''}")


def _get(results: dict[str, Any], key: str) -> Any:
    from probecommit.report.ledger import walk_dotted

    try:
        return walk_dotted(results, key.split("."))
    except KeyError:
        return None
