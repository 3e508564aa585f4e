"""``results/paper/claims.json``: the claims registry's statuses, computed from the results tree.

Why a file: REPRODUCTION.md prints the counts and each status through the ledger
(``"claims:counts.reproduced"``, ``"claims:claims.<id>.status"``), and ``verify`` can
recompute them from the same registry and results.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from probecommit.report.ledger import resolve
from probecommit.studies import paper_values
from probecommit.studies.claims import (CLAIMS, EXPERIMENTS, Outcome, counts, counts_simulated_rig, evaluate,
                                        explanations)
from probecommit.store.safefile import write_text

CLAIMS_NAME = "claims.json"
CLAIMS_VERSION = 1


def trees(root: Path) -> dict[str, Any]:
    """Every study's results.json under ``root``, by study name, plus the paper values."""
    out: dict[str, Any] = {"paper": paper_values.tree()}
    for path in sorted(root.glob("*/results.json")):
        out[path.parent.name] = json.loads(path.read_text())
    return out


def compute(root: str | Path) -> dict[str, Any]:
    """The claims payload for the publication ``root`` (``results/paper``)."""
    root = Path(root)
    loaded = trees(root)

    def lookup(key: str) -> Any:
        try:
            return resolve(key, root, loaded)
        except FileNotFoundError as exc:  # a study not published here: the key names nothing
            raise KeyError(key) from exc

    def exists(pattern: str) -> bool:
        return any(root.rglob(pattern))

    outcomes: dict[str, Outcome] = {c.id: evaluate(c, lookup, exists) for c in CLAIMS}
    entries = {}
    for claim in CLAIMS:
        o = outcomes[claim.id]
        entries[claim.id] = {
            "location": claim.location, "kind": claim.kind, "what": claim.what, "status": o.status,
            "passed": o.passed, "total": o.total, "failed": o.failed, "unresolved": o.unresolved,
            "experiment": o.experiment,
            "experiment_titles": [EXPERIMENTS[e].title for e in (o.experiment or "").split(", ") if e in EXPERIMENTS],
            "simulated_rig": claim.simulated_rig, "physical": claim.physical, "note": claim.note,
            "paper": {k: paper_values.PRINTED[k] for k in claim.paper_keys()},
            "comparisons": [{"label": c.label, "rule": c.rule, "ours": list(c.keys()) or getattr(c, "pattern", None)}
                            for c in claim.comparisons],
            "explain_candidates": [number for number, _ in explanations(claim)],
        }
    return {"version": CLAIMS_VERSION, "counts": counts(outcomes), "counts_simulated_rig": counts_simulated_rig(outcomes),
            "claims": entries}


def write(root: str | Path) -> Path:
    """Compute and write ``claims.json`` at the publication root."""
    path = Path(root) / CLAIMS_NAME
    write_text(path, json.dumps(compute(root), indent=1) + "\n")
    return path
