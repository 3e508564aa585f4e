"""Freeze a full reproduction into the repository: results/insertion/ and REPRODUCTION.md."""

from __future__ import annotations

import shutil
from pathlib import Path

from probecommit.report.verify import write_manifest
from probecommit.studies.explanations import EXPLANATIONS
from probecommit.report.reproduction_md import render

#: Result files small enough to version (the per-episode fault table stays in the run root).
PUBLISHED_SUFFIXES = (".md", ".json", ".png")
PUBLISHED_PARQUET = ("scan.parquet", "cover_search.parquet", "fault_signatures.parquet", "resplits.parquet", "gates_curves.parquet")

HEADER = """# Reproduction

Every number below was produced by this repository's code from a config in it:
`probecommit reproduce insertion` (or `make reproduce`) reruns the study from
`configs/paper/insertion.yaml` and rewrites this file and `results/insertion/`.
"paper" is the value the paper reports; "ours" is our frozen result with its
truth-cluster bootstrap interval where one applies. The note under each table says
where and why we differ. Nothing was tuned to move a downstream number toward the
paper's; the scene parameters we chose, and why, are in `docs/decisions.md`.

Scope: the MuJoCo insertion study (paper Sec. V A-C and VI). The other task
families, the PyBullet and PhysX insertion scenes and the physical-arm data are not
in this release.

"""


def publish_insertion(results_dir: str | Path, repo_root: str | Path) -> Path:
    """Copy the versionable results into ``results/insertion`` and write REPRODUCTION.md."""
    results_dir, repo_root = Path(results_dir), Path(repo_root)
    target = repo_root / "results" / "insertion"
    target.mkdir(parents=True, exist_ok=True)
    for path in sorted(results_dir.iterdir()):
        if path.suffix in PUBLISHED_SUFFIXES or path.name in PUBLISHED_PARQUET:
            shutil.copy2(path, target / path.name)
    body = render(results_dir / "results.json", EXPLANATIONS)
    (repo_root / "REPRODUCTION.md").write_text(HEADER + body)
    write_manifest(target)
    return target
