"""The ex23 helper's step (E162, E163), run by ``Explain.run``: Table III's uncovered optimism cells at the design's
exposure to the misread band (``ex23_band``).

It reads only stored runs (the insertion study's Split B random runs and the explain target's fresh draws, written
by ``Explain.draw_runs`` before it is set aside) and re-executes the calibrated arm's commits from their stored
probes, so it runs in a process of its own (``Explain.aside``). It stores the rows its keys come from, so
``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex20, ex20_band, ex23_band, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex23_band",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex23_band": ex23_band.STORED}
#: The Split B random runs of Table III.
CAL, TEST = "B_cal_random", "B_test_random"
#: The columns of a re-executed commit the rows keep.
COMMIT_COLUMNS = ("instance_id", "repeat", "k", "status", "predicted", "realized")


def _hits(loaded: Any) -> pd.DataFrame:
    """ex20's band rows of a run's stored original-arm episodes: ``instance_id, repeat, k, hit`` and the design."""
    return ex20._rows(loaded, loaded.path.name)


def _with_hits(table: pd.DataFrame, hits: pd.DataFrame) -> pd.DataFrame:
    ok = table.loc[table["status"].astype(str) != "failed", list(COMMIT_COLUMNS[:3]) + ["predicted", "realized"]]
    ok = ok.assign(instance_id=ok["instance_id"].astype(str), repeat=ok["repeat"].astype(np.int64),
                   k=ok["k"].astype(np.int64))
    return ok.merge(hits[["instance_id", "repeat", "k", "hit"]], on=["instance_id", "repeat", "k"], how="left",
                    validate="one_to_one")


def calibrated_rows(cal_loaded: Any, test_loaded: Any, alpha: float, grid: Any) -> pd.DataFrame:
    """E163's rows: the calibration run's worst-repeat scores with their instances' band exposure, its commits
    re-executed at the weighted t_k for every margin of the grid, and the test run's at the weighted t_k and
    margin, each row with its trajectory's band hit."""
    from probecommit.audit.conformal import conformal_rank, instance_scores
    from probecommit.runner.calibration import PROBE_METHOD, SCORE_COLUMNS, load_for_commit

    budgets = list(ex23_band.BUDGETS)
    cal_hits, test_hits = _hits(cal_loaded), _hits(test_loaded)
    design = {n: float(cal_hits[n].iloc[0]) for n in ex20_band.DESIGN}
    probe = cal_loaded.table("episodes", where=("method", [PROBE_METHOD]), columns=SCORE_COLUMNS)
    probe = probe.loc[probe["variant"] == "deployed"]
    wide = instance_scores(probe, None)
    exposed = cal_hits.groupby(["instance_id", "k"])["hit"].any()
    score = wide[budgets].stack().rename("score").reset_index()
    score["instance_id"] = score["instance_id"].astype(str)
    score = score.assign(k=score["k"].astype(np.int64))
    score["hit"] = exposed.reindex(pd.MultiIndex.from_frame(score[["instance_id", "k"]])).to_numpy(bool)
    rank = conformal_rank(int(wide.shape[0]), alpha)
    score["rank"] = rank
    for n, v in design.items():
        score[n] = v
    probabilities = ex23_band._probabilities(score)
    t_w = ex23_band.thresholds(score, probabilities, rank)["weighted"]
    grid = sorted((float(g) for g in grid), reverse=True)
    cal = load_for_commit(cal_loaded, budgets=budgets)
    keep = list(COMMIT_COLUMNS)
    tables = cal.commit(*[(t_w, g) for g in grid], keep=[keep] * len(grid), reduce=[_identity] * len(grid))
    margin = pd.concat([_with_hits(t, cal_hits).assign(gamma=g) for g, t in zip(grid, tables)], ignore_index=True)
    margin["threshold"] = margin["k"].map(t_w)
    cal.release()
    gamma, _ = ex23_band.weighted_margin(margin, probabilities, grid)
    test = load_for_commit(test_loaded, budgets=budgets)
    [table] = test.commit((t_w, gamma), keep=[keep], reduce=[_identity], final=True)
    test_rows = _with_hits(table, test_hits).assign(gamma=gamma)
    test_rows["threshold"] = test_rows["k"].map(t_w)
    parts = [score.assign(part="score"), margin.assign(part="margin"), test_rows.assign(part="test")]
    out = pd.concat(parts, ignore_index=True)
    for n, v in design.items():
        out[n] = v
    return out


def _identity(table: pd.DataFrame) -> pd.DataFrame:
    return table


def run(job: Any) -> None:
    """E162 on the fresh draws' stored episodes, E163 on the Split B random runs' re-executed commits."""
    from probecommit.runner.replay import load_run
    from probecommit.audit.margin import GAMMA_GRID

    job.progress("explain: Table III's uncovered optimism cells at the design's band exposure", 0, 1)
    parts = [ex20._rows(load_run(folder), folder.name).assign(part="draw")
             for folder in sorted(Path(job.runs).glob(f"{ex20.DRAW_PREFIX}[0-9][0-9]"))]
    with warnings.catch_warnings():  # a grid without a satisfied margin warns; the keys say so
        warnings.simplefilter("ignore", RuntimeWarning)
        parts.append(calibrated_rows(job.load(CAL), job.load(TEST), job.p.alpha, GAMMA_GRID))
    rows = pd.concat(parts, ignore_index=True)
    job.stored[ex23_band.STORED] = rows
    job.res["ex23_band"].update(ex23_band.keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, "ex23_band", ex23_band.STORED,
                                         lambda rows: ex23_band.keys(rows, boot))
