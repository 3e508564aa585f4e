"""Table III on fresh draws of Split B's test generator: how far its cells move with the draw alone.

The audit table's cells (cluster coverage and optimism per budget, original executor and
set-calibrated + margin executor) are statistics of one 96-instance test draw. Each fresh
draw (``runs.fresh_draws``) is audited with the *frozen* calibration (our Split B
calibration run's ``t_k`` and margin ``gamma``), so only the test draw changes. A paper
cell inside the range of the fresh draws is one that a draw of our generator gives; a cell
outside it is not explained by the draw.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.metrics import audit_table, summary_row
from probecommit.runner.calibration import load_for_commit
from probecommit.runner.calibration import calibrate

#: Table III's columns, as the insertion results name them.
METRICS = ("cluster_coverage", "optimism")
ARMS = ("original", "calibrated")


def draw_cells(run: Path, thresholds: Mapping[int, float], gamma: float, *, nominal: float, resamples: int,
               seed: int) -> dict[str, float]:
    """Table III's cells and bottom row on one test run, re-committed under a frozen calibration.

    Returns:
        ``<metric>.<arm>.k<k>`` and ``mean_abs_optimism.<arm>``, ``mean_abs_cluster_coverage_gap.<arm>``.
    """
    budgets = sorted(int(k) for k in thresholds)
    loaded = load_for_commit(run, budgets=budgets, chunk_instances=48)
    tables = loaded.commit((loaded.nu, None), (dict(thresholds), float(gamma)), final=True)
    out: dict[str, float] = {}
    for arm, table in zip(ARMS, tables):
        audit = audit_table(table, resamples=resamples, seed=seed)
        audit = audit[audit["k"].isin(budgets)].sort_values("k")
        for row in audit.itertuples():
            for metric in METRICS:
                out[f"{metric}.{arm}.k{int(row.k)}"] = float(getattr(row, metric))
        for name, v in summary_row(audit, nominal).items():
            out[f"{name}.{arm}"] = v
    return out


def spread(per_draw: Sequence[Mapping[str, float]]) -> dict[str, Any]:
    """Per cell: ``min``, ``max`` and ``mean`` over the draws (the range a paper cell is compared with)."""
    frame = pd.DataFrame(list(per_draw))
    out: dict[str, Any] = {}
    for cell in frame.columns:
        values = frame[cell].to_numpy(float)
        out[f"{cell}.min"], out[f"{cell}.max"] = float(np.min(values)), float(np.max(values))
        out[f"{cell}.mean"] = float(np.mean(values))
    return out


def fresh_calibration_cells(cal: Path, test: Path, budgets: Sequence[int], *, alpha: float) -> dict[str, float]:
    """Table III's calibrated cells when the calibration run is a fresh draw too (``calibrate`` on ``cal``,
    audited on ``test``), with the calibration's ``t_k`` and margin ``gamma``."""
    result = calibrate(cal, test, alpha=alpha, budgets=list(budgets), resamples=2, seed=0, chunk_instances=48)
    out: dict[str, float] = {"gamma": float(result.margin.gamma)}
    out.update({f"t_k{int(k)}": float(t) for k, t in result.thresholds.items()})
    for row in result.table3.to_dict("records"):
        for metric in METRICS:
            out[f"{metric}.calibrated.k{int(row['k'])}"] = float(row[f"{metric}_calibrated"])
    out["mean_abs_optimism.calibrated"] = float(result.summary["mean_abs_optimism_calibrated"])
    return out


def fresh_gate_cells(cal: Path, test: Path, *, alpha: float) -> dict[str, float]:
    """The random-probe commit gates' areas and mean failures on ``test`` with the decision layer calibrated on
    ``cal`` (the explain target's random-probe gates, on a pair of fresh draws), and whether posterior
    variance has the lowest area of the three deployable gates."""
    from probecommit.runner.calibration import gates
    from probecommit.studies.explain.pool import gate_pools

    pools = gate_pools(gates(cal, test, alpha=alpha, resamples=2, seed=0, chunk_instances=48))
    areas = {name: pools.get(f"{name}.area", float("nan")) for name in ("raw", "adjusted", "posterior_variance")}
    out = {f"{name}.area": v for name, v in areas.items()}
    out.update({f"{name}.mean_failure": pools.get(f"{name}.mean_failure", float("nan")) for name in areas})
    out["posterior_variance_lowest"] = float(min(areas, key=areas.get) == "posterior_variance")
    return out
