"""Cover-schedule search: the best five-tap subset on the development instances.

Every one of the C(9, 5) = 126 five-position subsets of the nine tap positions,
executed in increasing position order, is scored by its mean failure at k = 5 on
the development instances under the deployed model; ties go to the lower mean aim
error |a - x_hole|, then to the earlier subset in lexicographic order.
"""

from __future__ import annotations

from itertools import combinations
from typing import Iterator

import numpy as np
import pandas as pd

from probecommit.runner.build import build_executors, build_filter, build_model
from probecommit.runner.config import StudyConfig
from probecommit.runner.inference import build_trace, commit, rollout
from probecommit.runner.instances import draw_instances


def candidate_schedules(probe_grid: np.ndarray, size: int = 5) -> list[tuple[float, ...]]:
    positions = sorted(float(u) for u in np.asarray(probe_grid).reshape(-1))  # scalar taps
    return [tuple(combo) for combo in combinations(positions, size)]


def candidate_episodes(config: StudyConfig, simulator, limit: int | None = None,
                       progress=None) -> Iterator[tuple[int, tuple[float, ...], pd.DataFrame]]:
    """Each candidate schedule's episode table at its last tap on the development instances:
    ``(order, schedule, episodes)``. The search's own steps, shared by the search and by the
    explain target's resampling of it (``studies.explain.searches``)."""
    model = build_model(config)
    pfilter = build_filter(model, config.belief)
    executors = build_executors(["probe_robust"], model)
    instances = draw_instances(config, model)
    candidates = candidate_schedules(model.probe_grid)[:limit]
    for n, schedule in enumerate(candidates):
        batch = rollout(instances, config.repeats, [(u,) for u in schedule], len(schedule), model, simulator, config.seed)
        trace = build_trace(pfilter, batch, config.seed, [len(schedule)])
        yield n, schedule, commit(trace, model, simulator, executors, thresholds=config.belief.nu)
        if progress:
            progress(n + 1, len(candidates))


def search_cover_schedule(config: StudyConfig, simulator, limit: int | None = None, progress=None) -> pd.DataFrame:
    """Score every candidate schedule; returns one row per schedule, best first.

    Args:
        config: A development-set config (its schedule is replaced per candidate).
        simulator: Ground truth; its cache makes every candidate reuse the same taps.
        limit: Score only the first ``limit`` candidates (quick mode).
    """
    rows = [{"schedule": list(schedule), "failure": float(ep["realized"].mean()),
             "aim_error": float(np.mean(np.abs(ep["action"] - ep["z_true"]))), "order": n}
            for n, schedule, ep in candidate_episodes(config, simulator, limit, progress)]
    return pd.DataFrame(rows).sort_values(["failure", "aim_error", "order"], kind="stable").reset_index(drop=True)
