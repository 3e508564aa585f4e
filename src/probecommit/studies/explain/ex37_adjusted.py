"""T33's adjusted gate under the paper's cover schedule, on the same instances (E211; ex37, issue #36; rule declared
in ``docs/decisions.md``, "ex37", before its numbers).

Why: T33 says the committed pool at 60 % commitment holds escapes at several times the rejected pool's rate. E13
measured the raw and posterior-variance gates under the paper's schedule (the runs ``runs.schedule_runs`` makes on
Split B's calibration and test instances) from the raw executor's rows alone; the adjusted gate needs the calibrated
+ margin executor's aims, so it was measured under our schedule only. Here the commit gates are computed on the
paper's-schedule runs exactly as the insertion study computes them on ours (``runner.calibration.gates``: the
budget-simultaneous threshold, the margin searched under it); the adjusted gate's pool is read at the threshold
nearest 60 % commitment with E13's escape label (outside the full hull at the schedule's final budget, the raw
executor's ``escaped``), and its committed-to-rejected ratio gets E13's cluster-bootstrap interval. The two
executors' re-executed test rows are stored (:data:`STORED`); every key is :func:`keys` of them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

#: Result group and its stored rows (the raw and adjusted executors' test rows the gates read).
GROUP = "ex37_adjusted"
GROUPS = (GROUP,)
STORED = "ex37_adjusted_rows.parquet"
STORED_BY_GROUP = {GROUP: STORED}
#: The gates whose pools are published (the adjusted one is E211's; the other two check E13's rows).
SIGNALS = ("adjusted", "raw", "posterior_variance")
POOL = ("tau", "commit_rate", "n_committed", "escaped_committed", "n_rejected", "escaped_rejected", "claimed", "realized")


def stored_rows(record: Sequence[pd.DataFrame], threshold: float, gamma: float) -> pd.DataFrame:
    """The raw and adjusted requests of ``gates``' recorded rows (``request`` kept, the margin search's rows
    dropped), with the simultaneous threshold and the margin the adjusted executor ran at as columns (traced:
    recomputing them needs the calibration run's margin rows, which ``commits.parquet`` holds for Table IV only)."""
    rows = pd.concat(list(record), ignore_index=True)
    rows = rows[rows["request"].isin(["raw", "adjusted"])].drop(columns="gamma").reset_index(drop=True)
    rows["escaped"] = rows["escaped"].astype("boolean")
    return rows.assign(threshold=float(threshold), gamma=float(gamma))


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Each gate's pool at 60 % (``<signal>.<field>``, :data:`POOL`) and, for the adjusted gate, the committed and
    rejected escape rates and their ratio (``adjusted.final_hull.{committed_rate,rejected_rate,ratio}``, each
    ``[point, lo, hi]``), from the stored rows."""
    from probecommit.audit.gates import first_passage, gates_from_tables, trajectory_matrix
    from probecommit.studies.explain.stats import pool_escape_ratio

    part = lambda name: rows[rows["request"] == name].drop(columns="request").reset_index(drop=True)  # noqa: E731
    raw, adjusted = part("raw"), part("adjusted")
    summary = gates_from_tables(raw, adjusted).summary.set_index("signal")
    out: dict[str, Any] = {"threshold": float(rows["threshold"].iloc[0]), "gamma": float(rows["gamma"].iloc[0])}
    for signal in SIGNALS:
        for field in POOL[:-2] if signal == "posterior_variance" else POOL:  # it claims nothing; its realized is E13's
            value = summary.loc[signal, field]
            out[f"{signal}.{field}"] = int(value) if field.startswith(("n_", "escaped_")) else float(value)
    index, budgets, signal = trajectory_matrix(adjusted, "predicted")
    escaped = trajectory_matrix(raw, "escaped", budgets, index)[2][:, -1].astype(bool)
    committed = first_passage(signal, out["adjusted.tau"]) >= 0
    ratio = pool_escape_ratio(committed, escaped, index.get_level_values("instance_id").to_numpy(),
                              resamples=int(boot["resamples"]), seed=int(boot["seed"]))
    out.update({f"adjusted.final_hull.{name}": v for name, v in ratio.items()})
    out["trajectories"] = int(len(committed))
    return out


def run(job: Any) -> None:
    """E211 on the paper's-schedule runs (read from the explain target's run folders: the step runs in a process of
    its own after ``Explain.run`` made them)."""
    from probecommit.runner.calibration import gates
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex21 import PAPER_RUNS

    job.progress("explain: the adjusted gate under the paper's schedule (E211)", 0, 1)
    record: list[pd.DataFrame] = []
    result = gates(load_run(job.runs / PAPER_RUNS["cal"]), load_run(job.runs / PAPER_RUNS["test"]), alpha=job.p.alpha,
                   **job.boot, chunk_instances=48, record=record)
    rows = stored_rows(record, float(result.info["threshold"]), float(result.info["gamma"]))
    job.stored[STORED] = rows
    job.res[GROUP].update(keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    from probecommit.studies.explain import stored

    return stored.recompute_bootstrapped(folder, results, GROUP, STORED, lambda rows: keys(rows, boot))


__all__: Sequence[str] = ("run", "keys", "stored_rows", "recompute")
