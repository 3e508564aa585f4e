"""The ex20 helper's step (E144..E146), run by ``Explain.run``: Table III's original arm post-stratified on the
design's exposure to the misread band (``ex20_band``).

It reads only stored runs (the insertion study's random test run and the explain target's fresh draws, written
by ``Explain.draw_runs`` before it is set aside), so it runs in a process of its own (``Explain.aside``). It
stores the rows its keys come from, so ``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.studies.explain import ex20_band, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex20_band",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex20_band": ex20_band.STORED}
#: The explain target's fresh draws of Split B's random test generator (``Explain.draw_runs``).
DRAW_PREFIX = "analytic_draw_"


def _design(loaded: Any) -> dict[str, float]:
    """The design constants of a run: its prior box, the original boundary's ``r`` and the simulator's delta."""
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM

    cfg = loaded.config
    if cfg.model.boundary != "deployed":
        raise ValueError(f"{loaded.path}: ex20 reads the original (deployed) boundary, got {cfg.model.boundary!r}")
    lo, hi = cfg.model.prior_low, cfg.model.prior_high
    return {"x_low": float(lo[0]), "x_high": float(hi[0]), "c_low": float(lo[1]), "c_high": float(hi[1]),
            "r": TIP_RADIUS_MM, "delta": float(cfg.simulator.boundary_offset), "repeats": float(cfg.repeats)}


def _rows(loaded: Any, draw: str, budgets: tuple[int, ...] = ex20_band.BUDGETS) -> pd.DataFrame:
    return ex20_band.band_rows(loaded.table("episodes"), loaded.table("probes"), loaded.instances, draw, _design(loaded),
                               budgets)


def run(job: Any) -> None:
    """E144..E146 on Table III's random test run and the fresh draws of its generator."""
    from probecommit.runner.replay import load_run

    job.progress("explain: Table III's original arm at the design's exposure to the misread band", 0, 1)
    parts = [_rows(job.load(ex20_band.FROZEN), ex20_band.FROZEN)]
    for folder in sorted(Path(job.runs).glob(f"{DRAW_PREFIX}[0-9][0-9]")):
        parts.append(_rows(load_run(folder), folder.name))
    rows = pd.concat(parts, ignore_index=True)
    job.stored[ex20_band.STORED] = rows
    job.res["ex20_band"].update(ex20_band.keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, "ex20_band", ex20_band.STORED,
                                         lambda rows: ex20_band.keys(rows, boot))
