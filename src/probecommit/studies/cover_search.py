"""Cover-schedule search: the best five-tap subset on the development instances.

Every one of the C(9, 5) = 126 five-position subsets of the nine tap positions,
executed in increasing position order, is scored by its mean failure at k = 5 on
the development instances under the deployed model; ties go to the lower mean aim
error |a - x_hole|, then to the earlier subset in lexicographic order.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pandas as pd

from probecommit.runner.build import build_executors, build_filter, build_model
from probecommit.runner.config import StudyConfig
from probecommit.runner.inference import build_trace, commit, rollout
from probecommit.runner.instances import draw_instances


def candidate_schedules(probe_grid: np.ndarray, size: int = 5) -> list[tuple[float, ...]]:
    positions = sorted(float(u) for u in np.asarray(probe_grid).reshape(-1))  # scalar taps
    return [tuple(combo) for combo in combinations(positions, size)]


def search_cover_schedule(config: StudyConfig, simulator, limit: int | None = None, progress=None) -> pd.DataFrame:
    """Score every candidate schedule; returns one row per schedule, best first.

    Args:
        config: A development-set config (its schedule is replaced per candidate).
        simulator: Ground truth; its cache makes every candidate reuse the same taps.
        limit: Score only the first ``limit`` candidates (quick mode).
    """
    model = build_model(config)
    pfilter = build_filter(model, config.belief)
    instances = draw_instances(config, model)
    candidates = candidate_schedules(model.probe_grid)[:limit]
    rows = []
    for n, schedule in enumerate(candidates):
        batch = rollout(instances, config.repeats, [(u,) for u in schedule], len(schedule), model, simulator, config.seed)
        trace = build_trace(pfilter, batch, config.seed, [len(schedule)])
        ep = commit(trace, model, simulator, build_executors(["probe_robust"], model), thresholds=config.belief.nu)
        rows.append({
            "schedule": list(schedule),
            "failure": float(ep["realized"].mean()),
            "aim_error": float(np.mean(np.abs(ep["action"] - ep["z_true"]))),
            "order": n,
        })
        if progress:
            progress(n + 1, len(candidates))
    table = pd.DataFrame(rows).sort_values(["failure", "aim_error", "order"], kind="stable").reset_index(drop=True)
    return table
