"""Check the numerical invariants of frozen result files (``probecommit verify``).

A results tree holds one folder per study (``results/paper/insertion/``, ...), each with a
``results.json`` (the numbers the tables print), Parquet tables and figures, and a
``MANIFEST.json`` with the sha256 of every file. The verifier reads files only and
checks, without rerunning anything:

* **hashes**: every file listed in a study's manifest exists and matches; no result
  file is missing from it;
* **intervals**: every ``[point, lo, hi]`` triple has ``lo <= point <= hi``;
* **ranges**: rates (failure, coverage, escape, success, rates of commit) lie in [0, 1]
  and counts are non-negative integers;
* **identities**: optimism = realized - predicted; a paired ``a_minus_b`` equals
  ``a - b``; a ``failure_diff``/``paired_fix`` equals the difference of its rows;
  ``shift_vs_deployed_mm`` = delta + tip radius; the per-budget fault-signature table
  holds one row per (fault, k); a robot table's realized failure is ``1 - in_window /
  episodes``, its optimism ``realized - predicted``, its counts within ``0..episodes``;
* **counts**: ``n`` = 384 = 96 x 4 where the protocol says so;
* **traceability**: every number in ``REPRODUCTION.md``'s "ours" column is found,
  to the printed precision, in a ``results.json`` (and the key it came from is
  reported with ``--trace``).

Every check is one invariant; the report counts them and lists each failure in one line.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pandas as pd
from probecommit.store.manifest_rules import ManifestError, read_json, read_manifest
from probecommit.store.safefile import write_text

MANIFEST = "MANIFEST.json"
#: Result files that belong in a study's manifest.
RESULT_SUFFIXES = (".json", ".md", ".parquet", ".png", ".pdf", ".tex", ".html")
#: Keys whose numbers are probabilities or rates.
RATE_WORDS = ("failure", "coverage", "escape", "success", "commit_rate", "fail", "realized", "predicted")
#: Protocol sizes: rows of 96 instances x 4 repeats.
EPISODES_PER_ROW = 384
TOLERANCE = 1e-9


@dataclass
class Report:
    """Outcome of a verification: how many invariants, which failed."""

    checked: int = 0
    failures: list[str] = field(default_factory=list)
    traces: list[str] = field(default_factory=list)

    def check(self, ok: bool, message: str) -> None:
        self.checked += 1
        if not ok:
            self.failures.append(message)

    @property
    def ok(self) -> bool:
        return not self.failures


def sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def write_manifest(study_dir: str | Path) -> Path:
    """Write ``MANIFEST.json``: the sha256 of every result file of a study folder."""
    study_dir = Path(study_dir)
    files = sorted(p for p in study_dir.iterdir() if p.is_file() and p.suffix in RESULT_SUFFIXES and p.name != MANIFEST)
    manifest = {"sha256": {p.name: sha256_file(p) for p in files}}
    path = study_dir / MANIFEST
    write_text(path, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return path


# ----------------------------------------------------------------------------- walking


def _walk(node: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every (dotted key, value) of a JSON tree, lists of records included (``key[i]``)."""
    yield path, node
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _walk(value, f"{path}.{key}" if path else str(key))
    elif isinstance(node, list) and node and all(isinstance(v, dict) for v in node):
        for i, value in enumerate(node):
            yield from _walk(value, f"{path}[{i}]")


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _is_triple(x: Any) -> bool:
    return isinstance(x, list) and len(x) == 3 and all(_is_number(v) for v in x)


def _point(x: Any) -> float | None:
    if _is_number(x):
        return float(x)
    if _is_triple(x):
        return float(x[0])
    return None


def _last_word(key: str) -> str:
    return re.split(r"[.\[]", key)[-1].lower()


def _is_rate_key(key: str) -> bool:
    word = _last_word(key)
    if word.startswith("n_") or "escaped_" in word:  # counts of episodes
        return False
    if any(tag in word for tag in ("diff", "minus", "optimism", "delta", "gap", "paired", "_s", "auc")):
        return False
    return any(w in word for w in RATE_WORDS)


# ----------------------------------------------------------------------------- checks


def check_hashes(study: Path, report: Report) -> None:
    manifest_path = study / MANIFEST
    report.check(manifest_path.is_file(), f"{study}: no {MANIFEST} (hashes of the frozen files)")
    if not manifest_path.is_file():
        return
    try:  # the manifest rule set: named on error, never a traceback
        listed = read_manifest(manifest_path)["sha256"]
    except ManifestError as exc:
        report.check(False, str(exc))
        return
    for name, digest in sorted(listed.items()):
        path = study / name
        if not path.is_file():
            report.check(False, f"{study / name}: listed in {MANIFEST} but missing")
            continue
        report.check(sha256_file(path) == digest, f"{path}: sha256 differs from {MANIFEST} (the file changed)")
    for path in sorted(study.iterdir()):
        if path.is_file() and path.suffix in RESULT_SUFFIXES and path.name != MANIFEST:
            report.check(path.name in listed, f"{path}: a result file not in {MANIFEST}")


def check_json(study: Path, report: Report) -> dict[str, Any]:
    """Interval, range and identity invariants of ``results.json``; returns its flat numbers."""
    path = study / "results.json"
    report.check(path.is_file(), f"{study}: no results.json")
    if not path.is_file():
        return {}
    try:
        payload = read_json(path, "results file")
    except ManifestError as exc:
        report.check(False, str(exc))
        return {}
    numbers: dict[str, Any] = {}
    where = f"{path}"
    for key, value in _walk(payload):
        if _is_triple(value):
            p, lo, hi = value
            report.check(lo - TOLERANCE <= p <= hi + TOLERANCE, f"{where}: {key} = {p} lies outside its interval [{lo}, {hi}]")
            numbers[key] = value
        elif _is_number(value):
            # NaN stands for "no value" (a signal that makes no probability claim); infinity never.
            report.check(not math.isinf(float(value)), f"{where}: {key} is infinite")
            if math.isnan(float(value)):
                continue
            numbers[key] = value
        else:
            continue
        point = _point(value)
        if _is_rate_key(key) and point is not None:
            report.check(-TOLERANCE <= point <= 1 + TOLERANCE, f"{where}: {key} = {point} is a rate outside [0, 1]")
        if _last_word(key) in ("n", "n_episodes", "episodes", "scans", "candidates") and point is not None:
            report.check(point >= 0 and float(point).is_integer(), f"{where}: {key} = {point} is not a count")
    # Records that spell an interval as X, X_lo, X_hi (tables of rows).
    for key, node in _walk(payload):
        if isinstance(node, dict):
            for k in list(node):
                lo, hi = node.get(f"{k}_lo"), node.get(f"{k}_hi")
                if all(_is_number(v) for v in (node[k], lo, hi)):
                    value = [float(node[k]), float(lo), float(hi)]
                    report.check(lo - TOLERANCE <= node[k] <= hi + TOLERANCE,
                                 f"{where}: {key}.{k} = {node[k]} lies outside its interval [{lo}, {hi}]")
                    numbers[f"{key}.{k}[ci]"] = value
    _check_identities(payload, where, report)
    return numbers


def _check_identities(payload: dict, where: str, report: Report) -> None:
    for key, node in _walk(payload):
        if not isinstance(node, dict):
            continue
        pts = {k: _point(v) for k, v in node.items()}
        # a, b and a_minus_b
        for k, v in pts.items():
            m = re.fullmatch(r"(.+)_minus_(.+)", k)
            if m and v is not None and pts.get(m.group(1)) is not None and pts.get(m.group(2)) is not None:
                expected = pts[m.group(1)] - pts[m.group(2)]
                report.check(abs(v - expected) < 1e-9, f"{where}: {key}.{k} = {v} but {m.group(1)} - {m.group(2)} = {expected}")
        # optimism = realized failure - predicted score
        if all(pts.get(k) is not None for k in ("optimism", "failure", "predicted")):
            expected = pts["failure"] - pts["predicted"]
            report.check(abs(pts["optimism"] - expected) < 1e-9,
                         f"{where}: {key}.optimism = {pts['optimism']} but failure - predicted = {expected}")
        # robot table (Table IX): realized failure is the share of aims outside the window
        if all(pts.get(k) is not None for k in ("in_window", "episodes", "realized", "predicted", "optimism")):
            expected = 1.0 - pts["in_window"] / pts["episodes"]
            report.check(abs(pts["realized"] - expected) < 1e-9,
                         f"{where}: {key}.realized = {pts['realized']} but 1 - in_window / episodes = {expected}")
            report.check(abs(pts["optimism"] - (pts["realized"] - pts["predicted"])) < 1e-9,
                         f"{where}: {key}.optimism = {pts['optimism']} but realized - predicted = "
                         f"{pts['realized'] - pts['predicted']}")
            for count in ("in_window", "entered", "covered"):
                if pts.get(count) is not None:
                    report.check(0 <= pts[count] <= pts["episodes"],
                                 f"{where}: {key}.{count} = {pts[count]} is not within 0..episodes = {pts['episodes']}")
        if pts.get("n") is not None and key.startswith("robust"):
            report.check(pts["n"] == EPISODES_PER_ROW, f"{where}: {key}.n = {pts['n']}, expected {EPISODES_PER_ROW} (96 x 4)")
        # fault table: a paired fix is the difference of the fixed and faulty rows
        if all(pts.get(k) is not None for k in ("paired_fix", "fix", "fail")):
            expected = pts["fix"] - pts["fail"]
            report.check(abs(pts["paired_fix"] - expected) < 1e-9,
                         f"{where}: {key}.paired_fix = {pts['paired_fix']} but fix - fail = {expected}")
        if "shift_vs_deployed_mm" in pts and pts.get("delta") is not None:
            expected = pts["delta"] + 1.2  # the deployed boundary is hg - r, r = 1.2 mm
            report.check(abs(pts["shift_vs_deployed_mm"] - expected) < 1e-9,
                         f"{where}: {key}.shift_vs_deployed_mm = {pts['shift_vs_deployed_mm']} but delta + r = {expected}")


def check_parquet(study: Path, report: Report) -> dict[str, float]:
    """Range and shape invariants of every Parquet table of a study folder.

    Returns:
        Column means and SDs (``file:column.mean``), which REPRODUCTION.md may print.
    """
    summaries: dict[str, float] = {}
    for path in sorted(study.glob("*.parquet")):
        try:
            frame = pd.read_parquet(path)
        except Exception as exc:  # noqa: BLE001 - any unreadable table is one failed invariant
            report.check(False, f"{path}: unreadable ({type(exc).__name__})")
            continue
        report.check(len(frame) > 0, f"{path}: no rows")
        for column in frame.columns:
            values = frame[column]
            if not pd.api.types.is_numeric_dtype(values) or pd.api.types.is_bool_dtype(values):
                continue
            arr = values.to_numpy(dtype=float, na_value=np.nan)
            report.check(not np.isinf(arr).any(), f"{path}: column {column} holds infinities")
            finite = arr[np.isfinite(arr)]
            if len(finite):
                summaries[f"{study.name}/{path.name}:{column}.mean"] = float(finite.mean())
                if len(finite) > 1:
                    summaries[f"{study.name}/{path.name}:{column}.sd"] = float(finite.std(ddof=1))
            if _is_rate_key(column):
                bad = np.flatnonzero((arr < -TOLERANCE) | (arr > 1 + TOLERANCE))
                for row in bad[:5]:
                    report.check(False, f"{path}: {column} = {arr[row]} at row {row} is a rate outside [0, 1]")
                report.checked += int(np.isfinite(arr).sum()) - len(bad[:5])
        if {"fault", "k"} <= set(frame.columns):
            dup = frame.duplicated(["fault", "k"])
            report.check(not dup.any(), f"{path}: (fault, k) repeated, first at row {int(np.argmax(dup))}")
            counts = frame.groupby("fault")["k"].nunique()
            report.check(counts.nunique() == 1, f"{path}: faults have different budget sets {counts.to_dict()}")
        if {"commit_rate", "n_committed"} <= set(frame.columns) and "signal" in frame.columns:
            for signal, part in frame.groupby("signal"):
                rates = part.sort_values("tau")["commit_rate"].to_numpy()
                report.check(bool(np.all(np.diff(rates) >= -TOLERANCE)),
                             f"{path}: commit rate of signal {signal} decreases as the threshold grows")
    return summaries


_NUMBER = re.compile(r"(?<![\w.])[+-]?\d+\.\d+")


def check_reproduction(md: Path, numbers: dict[str, Any], report: Report) -> None:
    """Every number in REPRODUCTION.md's "ours" column traces to a results.json key.

    A section that says which target generated it ("Generated by `probecommit reproduce
    X`") is traced against X's own files only, so a number another study happens to
    repeat cannot stand in for a changed one.
    """
    if not md.is_file():
        report.check(False, f"{md}: missing")
        return
    all_candidates: list[tuple[str, float]] = []
    for key, value in numbers.items():
        if _is_triple(value):
            all_candidates += [(f"{key}[{i}]", float(v)) for i, v in enumerate(value)]
        else:
            all_candidates.append((key, float(value)))
    all_triples = {k: v for k, v in numbers.items() if _is_triple(v)}
    candidates, triples = all_candidates, all_triples

    def close(v: float, text: str) -> bool:
        digits = len(text.split(".")[1])
        return abs(v - float(text)) <= 0.5 * 10**-digits + 1e-12

    def owned_by(key: str, target: str) -> bool:
        return key.startswith(f"{target}:") or key.startswith(f"{target}/")

    header: list[str] | None = None
    for line_no, line in enumerate(md.read_text().splitlines(), start=1):
        if line.startswith("## "):  # a new section: traced against every study until it names its own
            candidates, triples = all_candidates, all_triples
        generated = re.search(r"Generated by `probecommit reproduce (\w+)`", line)
        if generated:
            target = generated.group(1)
            scoped = [(k, v) for k, v in all_candidates if owned_by(k, target)]
            if scoped:
                candidates = scoped
                triples = {k: v for k, v in all_triples.items() if owned_by(k, target)}
        if not line.strip().startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            continue
        if all(set(c) <= set("-: ") for c in cells):
            continue
        # Which cells are ours: the "ours" column of a paper-vs-ours table; otherwise
        # every cell of a row that is not the paper's own (its label says "paper").
        ours_cols = [i for i, h in enumerate(header) if h.startswith("ours") and "paper" not in h]
        if ours_cols:
            checked_cells = [cells[i] for i in ours_cols if i < len(cells)]
        elif "paper" in cells[0].lower():
            continue
        else:  # every cell but the label and the paper's own columns
            checked_cells = [c for i, c in enumerate(cells[1:], start=1) if i >= len(header) or "paper" not in header[i]]
        for cell in checked_cells:
            texts = _NUMBER.findall(cell)
            if len(texts) == 3 and "[" in cell:  # "point [lo, hi]": the three must come from one interval
                hits = [k for k, v in triples.items() if all(close(float(x), t) for x, t in zip(v, texts))]
                report.check(bool(hits), f"{md}:{line_no}: {cells[0]!r} prints {cell}, no results.json interval matches")
                if hits:
                    report.traces.append(f"{md.name}:{line_no} {cells[0]} {cell} <- {hits[0]}")
                continue
            for text in texts:
                hits = [k for k, v in candidates if close(v, text)]
                report.check(bool(hits), f"{md}:{line_no}: {cells[0]!r} prints {text}, found in no results.json")
                if hits:
                    report.traces.append(f"{md.name}:{line_no} {cells[0]} {text} <- {hits[0]}")


def verify(results_root: str | Path, reproduction_md: str | Path | None = None) -> Report:
    """Verify every study folder under ``results_root`` (or one study folder).

    Args:
        results_root: ``results/`` (every folder below it holding a ``results.json`` or a
            manifest is a study) or a single study folder.
        reproduction_md: REPRODUCTION.md to trace (default: beside ``results_root``'s parent
            when it exists).

    Returns:
        The report: invariants checked and one line per failure.
    """
    root = Path(results_root)
    if not root.is_dir():
        raise FileNotFoundError(f"no results folder at {root}")
    report = Report()
    studies = sorted({p.parent for name in ("results.json", MANIFEST) for p in root.rglob(name)})
    if not studies:
        raise FileNotFoundError(f"{root} holds no study folder (results.json / {MANIFEST})")
    numbers: dict[str, Any] = {}
    for study in studies:
        check_hashes(study, report)
        numbers.update({f"{study.name}:{k}": v for k, v in check_json(study, report).items()})
        numbers.update(check_parquet(study, report))
    if reproduction_md is None:  # the nearest REPRODUCTION.md above the results folder
        reproduction_md = next((p / "REPRODUCTION.md" for p in [root, *root.resolve().parents]
                                if (p / "REPRODUCTION.md").is_file()), None)
    if reproduction_md is not None:
        if not _check_ledger(root, report):
            check_reproduction(Path(reproduction_md), numbers, report)
    return report


def _check_ledger(root: Path, report: Report) -> bool:
    """Re-resolve every number of the published-numbers ledger, when the publication has one.

    Returns whether a ledger was found (then it replaces the heuristic trace of REPRODUCTION.md).
    """
    from probecommit.report import ledger
    from probecommit.studies.paper_values import tree

    publication = next((p for p in (root, root / "paper") if (p / ledger.LEDGER_NAME).is_file()), None)
    if publication is None:
        return False
    entries = ledger.read(publication)
    problems = list(ledger.check(entries, publication, {"paper": tree()}))
    report.checked += len(entries) - len(problems)
    for problem in problems:
        report.check(False, problem)
    report.traces += [f"{e.file}: {e.text} <- {e.key}" for e in entries]
    _check_claims(publication, report)
    return True


def _check_claims(publication: Path, report: Report) -> None:
    """claims.json's statuses recomputed from the registry and the results tree."""
    from probecommit.report import claims_json

    path = publication / claims_json.CLAIMS_NAME
    report.check(path.is_file(), f"{path}: missing (publishing writes the claims' statuses)")
    if not path.is_file():
        return
    stored, again = json.loads(path.read_text()), claims_json.compute(publication)
    report.check(stored.get("counts") == again["counts"],
                 f"{path}: counts {stored.get('counts')} but the registry recomputes {again['counts']}")
    for cid, entry in again["claims"].items():
        old = stored.get("claims", {}).get(cid, {})
        report.check((old.get("status"), old.get("experiment")) == (entry["status"], entry["experiment"]),
                     f"{path}: {cid} is {old.get('status')!r} but recomputes as {entry['status']!r}")
