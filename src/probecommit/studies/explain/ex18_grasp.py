"""Grasp's feasible truths against the gripper's force ceiling (E133; ex18, issue #36; rule declared in
``docs/decisions.md``, "ex18", "E133").

Why: a truth is feasible when some grid grip holds it without crushing it; our grip grid (0.2 N x 1.02^i up to 5 N
per pad) resolves the 1.5x window everywhere, so which truths are feasible is set by the grid's ceiling alone, a
parameter the paper does not report (ours: 13 feasible truths, the paper's six). This step reruns the frozen
MuJoCo grasp study with the gripper's ceiling at each declared value, applied to every force it exerts (the grip
grid and the squeeze forces keep their values at most the ceiling; nothing else changes), and counts the
per-truth signs as Table II reads them. The frozen family is not touched: the ceiling is applied to the model's
grids for the duration of one run (:func:`force_ceiling`), in the step's own process.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np
import pandas as pd

#: The stored rows the keys are counted from (``breadth.truth_rows`` per ceiling, ``ceiling`` in N per pad).
STORED = "ex18_grasp_rows.parquet"
#: Result group.
GROUP = "ex18_grasp"
#: The declared ceilings (N per pad); 5 is the frozen grid's own (a check that the frozen row is reproduced). A quick
#: run has them all (on the quick config's two truths: about a second a ceiling), so E133's keys resolve there too.
CEILINGS = (1.5, 2.0, 2.5, 3.0, 4.0, 5.0)


@contextmanager
def force_ceiling(limit: float) -> Iterator[None]:
    """The grasp model's grip and squeeze grids cut to forces at most ``limit`` (N per pad) inside the block, the
    frozen grids restored after it (whatever happens inside)."""
    from probecommit.tasks.grasp.model import ACTION_FORCES, PROBE_FORCES, GraspModel

    saved = GraspModel.action_grid, GraspModel.probe_grid
    probes = np.array([u for u in PROBE_FORCES if u <= limit + 1e-12], dtype=float)
    actions = ACTION_FORCES[ACTION_FORCES <= limit + 1e-12]
    if not len(probes) or not len(actions):
        raise ValueError(f"grasp force ceiling {limit} N leaves no squeeze or no grip force")
    GraspModel.action_grid, GraspModel.probe_grid = actions[:, None], probes[:, None]
    try:
        yield
    finally:
        GraspModel.action_grid, GraspModel.probe_grid = saved


def ceiling_config(limit: float, quick: bool, name: str | None = None) -> Any:
    """The frozen grasp config (MuJoCo), named after the ceiling (its run folder) unless ``name`` is given."""
    from probecommit.runner.config import config_data, parse_config
    from probecommit.studies.breadth import paper_config, quick_config

    base = paper_config("grasp")
    data = config_data(quick_config(base) if quick else base)
    data["name"] = name or f"grasp_force_ceiling{float(limit):g}"
    return parse_config(data)


def rows_of(runs: Path, ceilings: Sequence[float], quick: bool) -> pd.DataFrame:
    """Per ceiling, the run's ``truth_rows`` (``ceiling`` column): one MuJoCo grasp run each, serial (the ceiling
    lives in this process's model class, so no worker process may build its own)."""
    from probecommit.runner.study import run_study
    from probecommit.studies.breadth import truth_rows

    frames = []
    for limit in ceilings:
        config = ceiling_config(limit, quick)
        path = runs / config.name
        with force_ceiling(float(limit)):
            run_study(config, path, workers=1, threads=1)
            frames.append(truth_rows(config, path).assign(ceiling=float(limit)))
    return pd.concat(frames, ignore_index=True)


def label(limit: float) -> str:
    """A ceiling's key prefix: ``cap`` and the ceiling in tenths of a newton (2.5 N: ``cap25``)."""
    return f"cap{int(round(limit * 10)):02d}"


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per ceiling (``cap<tenths of N>.``, e.g. ``cap25`` for 2.5 N): the ceiling, feasible truths, improve / worsen /
    tie counts and the largest and smallest per-truth difference (``grasp_x.sign_counts``). One function for the step
    and verify."""
    from probecommit.studies.explain.grasp_x import sign_counts

    out: dict[str, Any] = {}
    for limit, r in rows.groupby("ceiling", sort=False):
        got = sign_counts(r.drop(columns=["ceiling"]), worst=True)
        out.update({f"{label(float(limit))}.{k}": v for k, v in {"ceiling": float(limit), **got}.items()})
    return out


def run(explain: Any) -> None:
    """The explain step, set aside to a process of its own (``Explain.aside``: the ceiling patches the model class
    in that process only): the reruns, their rows stored and the ``ex18_grasp`` keys counted from them."""
    explain.progress("explain: grasp against the gripper's force ceiling (E133)", 0, 1)
    rows = rows_of(explain.runs, CEILINGS, bool(explain.quick))
    explain.stored[STORED] = rows
    explain.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "rows_of", "force_ceiling", "ceiling_config", "CEILINGS")
