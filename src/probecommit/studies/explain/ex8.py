"""The ex8 explain helper's steps (E73..), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and reads only what ``Explain`` holds
(the rows earlier steps stored, the breadth study's stored tables under the root).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex4_grasp, ex8_blind, ex8_grasp, ex8_pybullet

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex8_grasp", "ex8_pybullet", "ex8_blind")


def run(job: Any) -> None:
    """Grasp truth by truth (E49's stored rows and Table II's, one particle rerun at c = 4); the PyBullet
    push's readings against the MuJoCo-fitted model (the frozen breadth runs' probes); Table II's blind cells over
    redrawn truth sets (the frozen blind episodes, the model; no engine run)."""
    job.progress("explain: grasp truth by truth against the paper's decomposition", 0, 1)
    keys, rows = ex8_grasp.run(job.root, job.runs, job.stored.get(ex4_grasp.STORED), job.quick, job.workers)
    job.res["ex8_grasp"].update(keys)
    job.stored[ex8_grasp.STORED] = rows
    job.progress("explain: 2-D push on PyBullet against the paper's residual model", 0, 1)
    keys, rows = ex8_pybullet.run(job.root, job.quick)  # the breadth study's frozen probes: no run
    job.res["ex8_pybullet"].update(keys)
    if len(rows):
        job.stored[ex8_pybullet.STORED] = rows
    job.progress("explain: Table II's blind cells over redrawn truth sets", 0, 1)
    draws = int(job.cfg["ex8_blind_draws_quick" if job.quick else "ex8_blind_draws"])
    keys, rows = ex8_blind.run(job.root, draws, job.quick)
    job.res["ex8_blind"].update(keys)
    if len(rows):
        job.stored[ex8_blind.STORED] = rows


#: Each group's own stored rows (published keys without them fail verify).
STORED_BY_GROUP = {"ex8_grasp": ex8_grasp.STORED, "ex8_pybullet": ex8_pybullet.STORED,
                   "ex8_blind": ex8_blind.STORED}


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex8's keys recomputed from a publication's stored rows (``verify``): ``(values, sources, problems)``, keyed
    as ``explain:results``; a group published without its stored rows is a problem."""
    values = {f"ex8_grasp.{k}": v for k, v in ex8_grasp.recompute(folder).items()}
    sources = dict.fromkeys(values, f"{ex8_grasp.STORED}, {ex4_grasp.STORED} and breadth/sign_flip_rows.parquet")
    pybullet = {f"ex8_pybullet.{k}": v for k, v in ex8_pybullet.recompute(folder).items()}
    values.update(pybullet)
    sources.update(dict.fromkeys(pybullet, ex8_pybullet.STORED))
    blind = {f"ex8_blind.{k}": v for k, v in ex8_blind.recompute(folder, results.get("ex8_blind", {})).items()}
    values.update(blind)
    sources.update(dict.fromkeys(blind, ex8_blind.STORED))
    problems = [f"explain/{name}: missing (the rows {group}'s keys are recomputed from)"
                for group, name in STORED_BY_GROUP.items() if results.get(group) and not (folder / name).is_file()]
    return values, sources, problems
