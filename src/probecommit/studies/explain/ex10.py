"""The ex10 helper's steps (E87..), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` from runs the root already holds and stores the rows its
summary comes from beside ``results.json`` (``Explain.stored``), so ``verify`` recomputes every key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex10_boundary, ex10_surprise

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex10_boundary", "ex10_surprise")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex10_boundary": ex10_boundary.STORED, "ex10_surprise": ex10_surprise.STORED}
#: The schedules step's stored rows of the paper's-schedule Split B test run (``studies.explain.stored.SCHEDULES``).
PAPER_TEST = "paper_B_test"


def run(job: Any, paper_schedule: dict[str, Any]) -> None:
    """E87: the engines study's PyBullet trajectories re-read with a boundary drawn afresh at every tap; E88: the
    paper's-schedule Split B test run replayed without the jitter's tail."""
    from probecommit.studies.paper_values import value

    job.progress("explain: PyBullet's boundary drawn per tap", 0, 1)
    keys, rows = ex10_boundary.run(job.root, [float(s) for s in job.cfg["ex10_boundary_sd_mm"]],
                                   value("T18-engine-scans.pybullet_offset"), job.boot)
    job.res["ex10_boundary"].update(keys)
    if rows is not None:
        job.stored[ex10_boundary.STORED] = rows
    job.progress("explain: surprise without the jitter's tail", 0, 1)
    keys, job.stored[ex10_surprise.STORED] = ex10_surprise.run(paper_schedule["test"], job.p.budgets["cover"], job.boot)
    job.res["ex10_surprise"].update(keys)


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key these steps publish, from their stored rows and the
    engines study's published episodes (``probecommit verify``; the contract of ``report.recompute.BOOTSTRAPPED``:
    ``results`` is not read here)."""
    import pandas as pd

    out: dict[str, tuple[Any, str]] = {}
    name = ex10_boundary.STORED
    if (folder / name).is_file():
        rows = pd.read_parquet(folder / name)
        episodes = folder.parent / "engines" / "engine_episodes.parquet"
        stored = pd.read_parquet(episodes) if episodes.is_file() else None
        for key, v in ex10_boundary.keys(rows, stored, boot).items():
            out[f"ex10_boundary.{key}"] = (v, name)
    name = ex10_surprise.STORED
    if (folder / name).is_file():
        from probecommit.studies.explain import stored as explain_stored

        schedules = folder / explain_stored.SCHEDULES
        table = pd.read_parquet(schedules) if schedules.is_file() else None
        test = None if table is None else table[table["run"] == PAPER_TEST]
        for key, v in ex10_surprise.keys(pd.read_parquet(folder / name), test, boot).items():
            out[f"ex10_surprise.{key}"] = (v, name)
    return out
