"""Development searches resampled: the cover schedule (T07) and the robust filters' tuning (T42).

Why: both of the paper's choices are winners of a search on 24 development instances and
ours differ. Each search is rerun here keeping every episode's outcome per candidate
(same instances, same taps, the same criterion and tie-break as the frozen search), then the
development instances are resampled (:func:`.choice.choice_stability`): how often does the
paper's candidate win, and is its paired gap to our winner distinguishable from zero?
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.build import build_executors, build_filter, build_model, build_simulator
from probecommit.runner.inference import build_trace, commit, rollout
from probecommit.runner.instances import draw_instances
from probecommit.runner.replay import LoadedRun, replay_episodes
from probecommit.studies.cover_search import candidate_schedules
from probecommit.studies.explain.choice import choice_stability
from probecommit.studies.robust import robust_candidates


def cover_episodes(protocol: Any,
                   limit: int | None = None) -> tuple[list[tuple[float, ...]], pd.DataFrame, pd.DataFrame]:
    """Every candidate schedule's per-episode failure and aim error on the development instances.

    The frozen search's own steps (``studies.cover_search``), kept per episode: returns the
    candidates, ``failure`` and ``aim_error`` tables ``[episodes, candidates]`` with the
    instance id as a column ``instance_id``.
    """
    cfg = protocol.run_config("cover-search", "development", "development", "cover")
    sim = build_simulator(cfg)
    model = build_model(cfg)
    pfilter = build_filter(model, cfg.belief)
    instances = draw_instances(cfg, model)
    candidates = candidate_schedules(model.probe_grid)[:limit]
    fail, aim, ids = {}, {}, None
    for n, schedule in enumerate(candidates):
        batch = rollout(instances, cfg.repeats, [(u,) for u in schedule], len(schedule), model, sim, cfg.seed)
        ep = commit(build_trace(pfilter, batch, cfg.seed, [len(schedule)]), model, sim, build_executors(["probe_robust"], model),
                    thresholds=cfg.belief.nu)
        ep = ep.sort_values(["instance_id", "repeat"], kind="stable")
        ids = ep["instance_id"].to_numpy() if ids is None else ids
        fail[n] = ep["realized"].to_numpy(float)
        aim[n] = np.abs(ep["action"] - ep["z_true"]).to_numpy(float)
    return candidates, pd.DataFrame(fail).assign(instance_id=ids), pd.DataFrame(aim).assign(instance_id=ids)


def cover_stability(protocol: Any, paper_schedule: list[float], boot: dict[str, Any],
                    limit: int | None = None) -> dict[str, Any]:
    """The cover search resampled over development instances; keys of ``explain:results.searches.cover.*``."""
    candidates, fail, aim = cover_episodes(protocol, limit)
    paper = tuple(float(u) for u in paper_schedule)
    out: dict[str, Any] = {"candidates": len(candidates), "paper_in_candidates": int(paper in candidates)}
    if paper not in candidates:
        return out
    target = candidates.index(paper)
    cols = list(range(len(candidates)))
    res = choice_stability(fail[cols].to_numpy(), fail["instance_id"].to_numpy(), target,
                           secondary=aim[cols].to_numpy(), **boot)
    means = fail[cols].mean().to_numpy()
    out.update({
        "winner": [float(u) for u in candidates[res["winner"]]],
        "paper_rank": int(1 + np.sum(means < means[target] - 1e-12)),
        "share_paper": res["share_target"], "share_winner": res["share_winner"],
        "failure_gap_paper_minus_winner": res["gap"],
        "aim_error_gap_paper_minus_winner": float(aim[target].mean() - aim[res["winner"]].mean()),
        "instances": int(fail["instance_id"].nunique()), "episodes": int(len(fail)),
    })
    return out


def robust_stability(development: LoadedRun, robust: Any, paper: dict[str, float],
                     boot: dict[str, Any]) -> dict[str, Any]:
    """The robust filters' development tuning resampled: share choosing the paper's value, and the gap.

    Per-episode final-budget failure of every grid value of each family (the tuning's
    criterion, ties to the first grid value), from replays of the development run.
    """
    cands = robust_candidates(robust.temperatures, robust.epsilons, robust.rejuvenation, robust.mixture_range)
    out: dict[str, Any] = {}
    for family, grid in cands.items():
        if family not in paper:
            continue
        columns, ids = [], None
        for _, belief in grid:
            ep, _ = replay_episodes(development, {"belief": belief}, chunk_instances=48)
            rows = ep[(ep.method == "probe_robust") & (ep.status == "ok")]
            rows = rows[rows.k == rows.k.max()].sort_values(["instance_id", "repeat"], kind="stable")
            ids = rows["instance_id"].to_numpy() if ids is None else ids
            columns.append(rows["realized"].to_numpy(float))
        values = [float(v) for v, _ in grid]
        target = int(np.argmin([abs(v - paper[family]) for v in values]))
        res = choice_stability(np.stack(columns, axis=1), ids, target, **boot)
        out[f"{family}.chosen"] = values[res["winner"]]
        out[f"{family}.paper_value_in_grid"] = int(abs(values[target] - paper[family]) < 1e-12)
        out[f"{family}.share_paper"] = res["share_target"]
        out[f"{family}.share_chosen"] = res["share_winner"]
        out[f"{family}.failure_gap_paper_minus_chosen"] = res["gap"]
    return out
