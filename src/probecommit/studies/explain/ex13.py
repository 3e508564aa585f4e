"""The ex13 helper's steps (E106..), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` from runs the root already holds (no new engine
run) and stores the rows its summary comes from beside ``results.json`` (``Explain.stored``), so ``verify``
recomputes every key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex13_mixture, ex13_surprise

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex13_surprise", "ex13_mixture")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex13_surprise": ex13_surprise.STORED, "ex13_mixture": ex13_mixture.STORED}
#: The re-split pool's run under the paper's schedule (``resplits.run`` writes it into the explain runs).
POOL_RUN = "B_pool_cover_paper_schedule"


def budgets(job: Any) -> tuple[int, int]:
    """The surprise budgets read: the first tap and the cover schedule's final budget."""
    return 1, int(job.p.budgets["cover"])


def run(job: Any, paper_schedule: dict[str, Any]) -> None:
    """E106: the surprise AUC at k = 1 and k = 5 over five draws of the generator under the paper's schedule;
    E107: the harness's right model replayed with the mixture under every reading of q0's units."""
    surprise(job, paper_schedule)
    mixture(job)


def surprise(job: Any, paper_schedule: dict[str, Any]) -> None:
    """E106 from the paper's-schedule runs and the re-split pool's run (``resplits`` wrote it; none: four draws)."""
    from probecommit.runner.replay import load_run

    job.progress("explain: surprise over five draws of the generator", 0, 1)
    pool = job.runs / POOL_RUN
    loaded = load_run(pool) if (pool / "episodes.parquet").is_file() else None
    keys, job.stored[ex13_surprise.STORED] = ex13_surprise.run(paper_schedule, loaded, budgets(job), job.boot)
    job.res["ex13_surprise"].update(keys)


def mixture(job: Any) -> None:
    """E107 on the fault harness's base run (right model), at the paper's epsilon."""
    from probecommit.studies.paper_values import value

    job.progress("explain: the mixture under every reading of q0's units", 0, 1)
    r, seeds = job.p.robust, int(job.cfg["ex13_mixture_seeds_quick" if job.quick else "ex13_mixture_seeds"])
    base = job.load("faults_base")
    keys, job.stored[ex13_mixture.STORED] = ex13_mixture.run(
        base, value("T42-robust-chosen.mixture"), float(r.mixture_range[0]), float(r.mixture_range[1]),
        [base.config.seed + i for i in range(seeds)], job.p.budgets["random"])
    job.res["ex13_mixture"].update(keys)


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key these steps publish, from their stored rows
    (``probecommit verify``; the contract of ``report.recompute.BOOTSTRAPPED``)."""
    import pandas as pd

    out: dict[str, tuple[Any, str]] = {}
    name = ex13_surprise.STORED
    if (folder / name).is_file():
        rows = pd.read_parquet(folder / name)
        ks = sorted(int(c.removeprefix("surprise_k")) for c in rows.columns if c.startswith("surprise_k"))
        for key, v in ex13_surprise.summary(rows, (ks[0], ks[-1]), **boot).items():
            out[f"ex13_surprise.{key}"] = (v, name)
    name = ex13_mixture.STORED
    if (folder / name).is_file():
        for key, v in ex13_mixture.summary(pd.read_parquet(folder / name)).items():
            out[f"ex13_mixture.{key}"] = (v, name)
    return out
