"""Table V's cover cells under the paper's cover schedule, on Test C's instances (E208; ex36, issue #36; rule declared
in ``docs/decisions.md``, "ex36", before any number was computed).

Why: Table V's cover cells are read on the schedule our cover search picks on our scene ([-9, -3, 3, 6, 12] mm);
the paper froze [-12, -6, 0, 6, 9] mm (Sec. V-A). At k = 1 the paper's schedule taps the prior's edge only, so the
k = 1 cells are where the schedule matters most; E9 showed on Split B that the schedule moves the k = 5 cell. This
step reruns the insertion study's ``C_cover`` with the paper's schedule and nothing else changed (same split name,
hence the same instances and tap-noise streams; MuJoCo) and replays it under the corrected boundary, as the study
builds ``C_cover_corrected`` (``runs.testc_schedule_runs``), then computes Table V's six cover cells as the study does
(``insertion.episode_metrics``, ``insertion.paired``) and tests each with Table V's own comparison from the claims
registry. It stores both arms' Probe-Robust rows, so ``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import pandas as pd

from probecommit.studies.explain import stored

#: The result group this step fills, and the rows its keys are summarized from.
GROUP = "ex36_testc"
GROUPS = (GROUP,)
STORED = "ex36_testc_rows.parquet"
STORED_BY_GROUP = {GROUP: STORED}
#: Table V's cover rows and the budget each is read at.
ROWS = {"failure_cover_k1": 1, "failure_cover_k5": 5}
#: Table V's columns: our key's last part -> the label's suffix in the claims registry.
COLUMNS = {"old": "old", "corrected": "corrected", "old_minus_corrected": "old - corrected"}
#: The episode columns the keys read (``insertion.episode_metrics`` and ``paired``), and the model column.
KEPT = ("instance_id", "repeat", "k", "method", "status", "predicted", "realized", "covered", "escaped")


def arm_rows(episodes: pd.DataFrame, model: str) -> pd.DataFrame:
    """One arm's Probe-Robust rows at every budget, labelled with its model (``old`` or ``corrected``)."""
    from probecommit.studies.insertion import probe_rows

    return probe_rows(episodes)[list(KEPT)].assign(model=model).reset_index(drop=True)


def run_rows(protocol: Any, runs: Path, workers: int) -> pd.DataFrame:
    """The paper's-schedule run of Test C and its corrected replay (``runs.testc_schedule_runs``), as stored rows."""
    from probecommit.studies.explain.runs import testc_schedule_runs
    from probecommit.studies.explain.study import COVER_SCHEDULE

    old, corrected = testc_schedule_runs(protocol, COVER_SCHEDULE, runs, workers)
    return pd.concat([arm_rows(old.episodes, "old"), arm_rows(corrected.episodes, "corrected")], ignore_index=True)


def cells(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Table V's cover cells as the insertion study computes them: ``<row>.old``, ``<row>.corrected`` (failure with its
    cluster-bootstrap interval) and ``<row>.old_minus_corrected`` (paired, identical taps)."""
    from probecommit.studies.insertion import episode_metrics, paired

    old, new = (rows[rows["model"] == m] for m in ("old", "corrected"))
    out: dict[str, Any] = {}
    for row, k in ROWS.items():
        out[f"{row}.old"] = episode_metrics(old, k, **boot)["failure"]
        out[f"{row}.corrected"] = episode_metrics(new, k, **boot)["failure"]
        out[f"{row}.old_minus_corrected"] = paired(new, old, k, "realized", **boot)
    return out


def outcomes(values: Mapping[str, Any]) -> dict[str, float]:
    """``passes.<row>.<column>``: 1 where Table V's own comparison of that label (the registry's, its key read from
    ``values``) passes, else 0; how many of the six pass (``passes.count``) and of the labels our schedule fails
    (``passes.failing_count``, the registry's ``TESTC_SCHEDULE_FAILING``); ``holds``: 1 when all of those pass (E208's
    rule)."""
    from probecommit.studies.claims import CLAIMS, TESTC_SCHEDULE_FAILING

    testc = {c.label: c for c in next(c for c in CLAIMS if c.id == "tab:testc").comparisons}
    lookup = lambda key: values[key.split("table_testc.", 1)[1]]  # noqa: E731
    passed = {f"{row} {suffix}": float(testc[f"{row} {suffix}"].test(lookup)) for row in ROWS for suffix in COLUMNS.values()}
    out = {f"passes.{row}.{column}": passed[f"{row} {suffix}"] for row in ROWS for column, suffix in COLUMNS.items()}
    out["passes.count"] = float(sum(passed.values()))
    out["passes.failing_count"] = float(sum(passed[label] for label in TESTC_SCHEDULE_FAILING))
    out["holds"] = float(out["passes.failing_count"] == len(TESTC_SCHEDULE_FAILING))
    return out


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Every key of the step from its stored rows: the cells (:func:`cells`), their outcomes (:func:`outcomes`) and
    the trajectories per arm (``trajectories``)."""
    out = cells(rows, boot)
    out.update(outcomes(out))
    out["trajectories"] = float(len(rows[(rows["model"] == "old") & (rows["k"] == max(ROWS.values()))]))
    return out


def run(job: Any) -> None:
    """E208: the run and its replay in a process of their own (their tables leave with it), then the keys."""
    from probecommit.runner.aside import in_own_process

    job.progress("explain: Test C's cover cells under the paper's schedule (E208)", 0, 1)
    rows = in_own_process(run_rows, job.p, job.runs, job.workers)
    job.stored[STORED] = rows
    job.res[GROUP].update(keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, GROUP, STORED, lambda rows: keys(rows, boot))
