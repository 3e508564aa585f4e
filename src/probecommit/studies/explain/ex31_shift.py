"""Table III's original arm with each budget read one tap later (E193; docs/decisions.md, "ex31").

Why: ours is not low at k = 2 alone. At the design's exact exposure to the misread band (ex20) the paper's original
optimism sits near ours one tap later at every budget, and its k = 1 escape (Table III's run and its fault harness)
needs about two taps' band exposure: under the design one tap can escape only when it hits the band.
How a budget counts its taps is never stated; a pipeline that taps once before the first counted tap, or reads the
belief at a 0-based tap index, reports at k what ours reports at k + 1. This step reads Table III's own stored run
at k + 1 taps for every Table III budget k whose k + 1 is stored (the run taps eight times, so k = 8 is not read),
with ex20's estimator unchanged: optimism and cluster coverage post-stratified on the design's exact band exposure
at k + 1 taps, under Table III's cluster bootstrap. No engine run and no belief recomputed; it stores its rows, so
``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex20, ex20_band, stored

#: The result group this step fills (added to ``Explain.res``), and the rows its keys are summarized from.
GROUP = "ex31_shift"
GROUPS = (GROUP,)
STORED = "ex31_shift_rows.parquet"
STORED_BY_GROUP = {GROUP: STORED}
#: Table III's budgets whose shifted reading is stored (k + 1 <= 8, the random run's last tap), and the shift.
PAPER_BUDGETS = (1, 2, 3, 5)
SHIFT = 1
#: The tap counts read (one per Table III budget above).
TAPS = tuple(k + SHIFT for k in PAPER_BUDGETS)
#: ``ex20_band.frozen_keys``'s summaries over budgets, which mean nothing over shifted tap counts (not published).
LEFT_OUT = ("mean_abs_optimism", "mean_abs_optimism_std")


def escape_keys(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]]) -> dict[str, Any]:
    """Per tap count: the share of trajectories whose truth left the hull, raw and post-stratified on a band hit
    at the design's exact ``p`` (as ex20 post-stratifies optimism; beside the rule)."""
    out: dict[str, Any] = {}
    for k, at in rows.groupby("k", sort=True):
        hit, esc = at["hit"].to_numpy(bool), at["escaped"].to_numpy(float)
        p = probabilities[int(k)][0]
        e1 = float(esc[hit].mean()) if hit.any() else float("nan")
        e0 = float(esc[~hit].mean()) if (~hit).any() else float("nan")
        out.update({f"escape.k{int(k)}": float(esc.mean()), f"escape_hit.k{int(k)}": e1,
                    f"escape_free.k{int(k)}": e0, f"escape_std.k{int(k)}": p * e1 + (1 - p) * e0})
    return out


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Every key of the step from its stored rows: ex20's post-stratified cells per tap count (``.k<taps>``), the
    escape beside them, and the shift itself."""
    from probecommit.tasks.insertion.model import InsertionModel

    positions = [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]
    first = rows.iloc[0]
    taps = sorted(int(k) for k in rows["k"].unique())
    probabilities = ex20_band.design_probabilities(positions, {n: float(first[n]) for n in ex20_band.DESIGN}, taps)
    cells = ex20_band.frozen_keys(rows, probabilities, int(boot["resamples"]), int(boot["seed"]))
    out = {k: v for k, v in cells.items() if k not in LEFT_OUT}
    out.update(escape_keys(rows, probabilities))
    out["shift"] = SHIFT
    return out


def run(job: Any) -> None:
    """E193 on Table III's stored random test run, read at k + 1 taps."""
    job.progress("explain: Table III's original arm read one tap later", 0, 1)
    rows = ex20._rows(job.load(ex20_band.FROZEN), ex20_band.FROZEN, TAPS)
    job.stored[STORED] = rows
    job.res[GROUP].update(keys(rows, job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, GROUP, STORED, lambda rows: keys(rows, boot))
