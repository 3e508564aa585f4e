"""The fourth session's third explain helper's steps (E62..E64), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and reads only what ``Explain``
already holds (the root's frozen runs, the paper's-schedule runs, the random-gate step's
recorded rows, the bootstrap settings, the config); the rows each summary comes from are
stored beside ``results.json`` (``Explain.stored``).
"""

from __future__ import annotations

from typing import Any

from probecommit.studies.explain import ex6_gates, ex6_probes, ex6_surprise

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex6_probe_rule", "ex6_random_gates", "ex6_surprise")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex6_probe_rule": ex6_probes.STORED, "ex6_random_gates": ex6_gates.STORED,
                   "ex6_surprise": ex6_surprise.STORED}


def run(job: Any, paper_schedule: dict[str, Any]) -> None:
    """E62 (PyBullet's taps without replacement), E63 (the random gates over one range), E64 (surprise readings)."""
    job.progress("explain: PyBullet's taps drawn without replacement", 0, 1)
    keys, rows = ex6_probes.run(job.root, job.boot)
    job.res["ex6_probe_rule"].update(keys)
    if rows is not None:
        job.stored[ex6_probes.STORED] = rows
    job.progress("explain: the random-probe gates over one range", 0, 1)
    resamples = job.cfg["ex6_gate_resamples_quick" if job.quick else "ex6_gate_resamples"]
    keys, rows = ex6_gates.run(job.tables.pop("random_gates_record", []), resamples, job.boot["seed"])
    job.res["ex6_random_gates"].update(keys)
    if rows is not None:
        job.stored[ex6_gates.STORED] = rows
    job.progress("explain: surprise under every reading", 0, 1)
    keys, job.stored[ex6_surprise.STORED] = ex6_surprise.run(paper_schedule["test"], job.p.budgets["cover"], job.boot)
    job.res["ex6_surprise"].update(keys)


def recompute(folder: Any, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key these steps summarize from their stored rows,
    recomputed from the rows alone (``probecommit verify``). ``boundary_offset`` is a copy of the engines study's
    scan (traced); the gates' resample count is the published one."""
    import pandas as pd

    out: dict[str, tuple[Any, str]] = {}
    steps = ((ex6_probes.STORED, "ex6_probe_rule", lambda rows: ex6_probes.summary(rows, boot)),
             (ex6_surprise.STORED, "ex6_surprise", lambda rows: ex6_surprise.summary(rows, **boot)),
             (ex6_gates.STORED, "ex6_random_gates", lambda rows: ex6_gates.summary(
                 rows, int(results.get("ex6_random_gates", {}).get("bootstrap.resamples", 0)), boot["seed"])))
    for name, group, summarize in steps:
        if (folder / name).is_file():
            for key, value in summarize(pd.read_parquet(folder / name)).items():
                out[f"{group}.{key}"] = (value, name)
    return out
