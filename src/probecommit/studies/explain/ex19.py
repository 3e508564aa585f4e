"""The ex19 helper's steps (E138..), run by ``Explain.run`` after the prior-width sweep (``more``).

Each step writes one result group of ``explain:results`` and stores the rows its keys come from beside
``results.json`` (``Explain.stored``), so ``verify`` recomputes every key. The darts step reads the runs of the
prior-width sweep (E38) and its published keys, so it runs in place once that sweep is done; it runs no engine.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex19_cone, ex19_darts, stored

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex19_darts", "ex19_widths", "ex19_cone")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex19_darts": ex19_darts.STORED, "ex19_widths": ex19_darts.STORED_WIDTHS,
                   "ex19_cone": ex19_cone.STORED}


def run(job: Any) -> None:
    """E138: darts' row at E38's widths with its truth set redrawn (the model on stored blind actions); E140, E141:
    the hinge's and push1d's rows under the same rule."""
    job.progress("explain: Table II's rows at the prior's widths with their truths redrawn", 0, 1)
    keys, rows = ex19_darts.run(job.root, job.runs, job.cfg, job.res["breadth_prior"], job.quick)
    job.res["ex19_darts"].update(keys)
    if len(rows):
        job.stored[ex19_darts.STORED] = rows
    keys, rows = ex19_darts.run_widths(job.root, job.runs, job.cfg, job.res["breadth_prior"], job.quick)
    job.res["ex19_widths"].update(keys)
    if len(rows):
        job.stored[ex19_darts.STORED_WIDTHS] = rows


def cone(job: Any) -> None:
    """E139: 2-D push under the pyramidal cone over E95's pool (its stored actions and the frozen blind actions
    re-executed in the frozen scene under both cones). Set aside after ``ex11.run``, whose pool run it reads."""
    job.progress("explain: 2-D push under the pyramidal cone over redrawn truth sets", 0, 1)
    draws = int(job.cfg["ex19_cone_draws_quick" if job.quick else "ex19_cone_draws"])
    keys, rows = ex19_cone.run(job.root, job.runs, draws, job.quick)
    job.res["ex19_cone"].update(keys)
    if len(rows):
        job.stored[ex19_cone.STORED] = rows


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex19's keys recomputed from a publication's stored rows (``verify``; ``stored.recompute_group``)."""
    values, sources, problems = stored.recompute_group(folder, results, "ex19_darts", ex19_darts.STORED,
                                                       ex19_darts.recompute)
    for group, name, recompute_one in (("ex19_widths", ex19_darts.STORED_WIDTHS, ex19_darts.recompute_widths),
                                       ("ex19_cone", ex19_cone.STORED, ex19_cone.recompute)):
        more = stored.recompute_group(folder, results, group, name, recompute_one)
        values, sources, problems = values | more[0], sources | more[1], problems + more[2]
    return values, sources, problems
