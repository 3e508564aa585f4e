"""Development searches resampled: the cover schedule (T07) and the robust filters' tuning (T42).

Why: both of the paper's choices are winners of a search on 24 development instances and
ours differ. Each search is rerun here keeping every episode's outcome per candidate
(same instances, same taps, the same criterion and tie-break as the frozen search), then the
development instances are resampled (:func:`.choice.choice_stability`): how often does the
paper's candidate win, and is its paired gap to our winner distinguishable from zero?
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.build import build_simulator
from probecommit.studies.cover_search import candidate_episodes
from probecommit.studies.explain.choice import choice_stability


def cover_episodes(protocol: Any,
                   limit: int | None = None) -> tuple[list[tuple[float, ...]], pd.DataFrame, pd.DataFrame]:
    """Every candidate schedule's per-episode failure and aim error on the development instances.

    The frozen search's own steps (``studies.cover_search``), kept per episode: returns the
    candidates, ``failure`` and ``aim_error`` tables ``[episodes, candidates]`` with the
    instance id as a column ``instance_id``.
    """
    cfg = protocol.run_config("cover-search", "development", "development", "cover")
    candidates, fail, aim, ids = [], {}, {}, None
    for n, schedule, ep in candidate_episodes(cfg, build_simulator(cfg), limit):
        candidates.append(schedule)
        ep = ep.sort_values(["instance_id", "repeat"], kind="stable")
        ids = ep["instance_id"].to_numpy() if ids is None else ids
        fail[n] = ep["realized"].to_numpy(float)
        aim[n] = np.abs(ep["action"] - ep["z_true"]).to_numpy(float)
    return candidates, pd.DataFrame(fail).assign(instance_id=ids), pd.DataFrame(aim).assign(instance_id=ids)


#: The cover search's per-episode rows (``candidate``: its index in the search's order, ``schedule`` as JSON).
COVER_STORED = "cover_search_episodes.parquet"


def cover_table(protocol: Any, limit: int | None = None) -> pd.DataFrame:
    """The cover search's rows, one per (candidate, episode): failure and aim error (``cover_episodes``)."""
    candidates, fail, aim = cover_episodes(protocol, limit)
    ids = fail["instance_id"].to_numpy()
    parts = [pd.DataFrame({"candidate": n, "schedule": json.dumps([float(u) for u in schedule]), "instance_id": ids,
                           "failure": fail[n].to_numpy(float), "aim_error": aim[n].to_numpy(float)})
             for n, schedule in enumerate(candidates)]
    return pd.concat(parts, ignore_index=True).astype({"candidate": "int16"})


def cover_stability(table: pd.DataFrame, paper_schedule: list[float], boot: dict[str, Any]) -> dict[str, Any]:
    """The cover search resampled over development instances, from its stored rows (``cover_table``); keys of
    ``explain:results.searches.cover.*``."""
    order = table.drop_duplicates("candidate").sort_values("candidate")
    candidates = [tuple(float(u) for u in json.loads(sched)) for sched in order["schedule"]]
    table = table.assign(row=table.groupby("candidate").cumcount())  # the episode's position in its candidate's rows
    fail = table.pivot(index="row", columns="candidate", values="failure")
    aim = table.pivot(index="row", columns="candidate", values="aim_error")
    ids = table[table["candidate"] == order["candidate"].iloc[0]]["instance_id"].to_numpy()
    paper = tuple(float(u) for u in paper_schedule)
    out: dict[str, Any] = {"candidates": len(candidates), "paper_in_candidates": int(paper in candidates)}
    if paper not in candidates:
        return out
    target = candidates.index(paper)
    res = choice_stability(fail.to_numpy(float), ids, target, secondary=aim.to_numpy(float), **boot)
    means = fail.mean().to_numpy()
    out.update({
        "winner": [float(u) for u in candidates[res["winner"]]],
        "paper_rank": int(1 + np.sum(means < means[target] - 1e-12)),
        "share_paper": res["share_target"], "share_winner": res["share_winner"],
        "failure_gap_paper_minus_winner": res["gap"],
        "aim_error_gap_paper_minus_winner": float(aim[target].mean() - aim[res["winner"]].mean()),
        "instances": int(pd.Series(ids).nunique()), "episodes": int(len(ids)),
    })
    return out


def robust_stability(tuning: pd.DataFrame, paper: dict[str, float], boot: dict[str, Any]) -> dict[str, Any]:
    """The robust filters' development tuning resampled: share choosing the paper's value, and the gap.

    Per-episode final-budget failure of every grid value of each family (the tuning's criterion, ties to
    the first grid value), from the tuning's own replays of the development run as the insertion study
    stores them (``robust_episodes.parquet``, part ``tuning``: one function for the explain step and verify).
    """
    from probecommit.studies.robust import final_rows

    out: dict[str, Any] = {}
    for family, part in tuning.groupby("family", sort=False):
        if family not in paper:
            continue
        columns, ids, values = [], None, []
        for value, rows in part.groupby("value", sort=False):
            rows = final_rows(rows).sort_values(["instance_id", "repeat"], kind="stable")
            ids = rows["instance_id"].to_numpy() if ids is None else ids
            columns.append(rows["realized"].to_numpy(float))
            values.append(float(value))
        target = int(np.argmin([abs(v - paper[family]) for v in values]))
        res = choice_stability(np.stack(columns, axis=1), ids, target, **boot)
        out[f"{family}.chosen"] = values[res["winner"]]
        out[f"{family}.paper_value_in_grid"] = int(abs(values[target] - paper[family]) < 1e-12)
        out[f"{family}.share_paper"] = res["share_target"]
        out[f"{family}.share_chosen"] = res["share_winner"]
        out[f"{family}.failure_gap_paper_minus_chosen"] = res["gap"]
    return out
