"""Do PhysX's solver iterations give the paper's 0.55 x capture window, and its boundary? (E226; ex40, issue #36;
rule declared in ``docs/decisions.md``, "ex40", before the sweep on more than two truths.)

Why: ex38 found no shape offset that gives the paper's PhysX window and boundary together. A scene rebuilt
"parameter for parameter" from MuJoCo's copies the timestep and the drives but keeps PhysX's solver iteration counts
at SAPIEN's defaults (10 position, 1 velocity; ours 32 and 4), and fewer iterations leave the peg's friction and
contacts less converged, which narrows the window. The sweep runs the engines study's two scans at each declared
(position, velocity) count on both probes' articulations, every other setting ours; the point is chosen by the
window the paper reports and judged on the boundary, both within T18's tolerances (ex38's rule, one arm). Every key
is :func:`summary` of the stored scan rows.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import pandas as pd

from probecommit.studies.explain import ex38_physx

#: The stored rows (``engines.scan_rows`` per point, with its grid index ``value`` and counts), beside results.json.
STORED = "ex40_solver_rows.parquet"
#: Result group.
GROUP = "ex40_solver"
#: The declared grid, (position, velocity) iterations in the declared order: ours, SAPIEN's default, down to the
#: least PhysX accepts. A point's ``value`` is its index here, so ties of the window go to the first in this order.
GRID = ((32, 4), (10, 1), (4, 1), (2, 1), (1, 1), (1, 0))
#: A quick run's points (indices): ours and the solver's floor.
QUICK = (0, 5)
#: The arm's name in the stored rows (ex38's summary reads rows by arm and value).
ARM = "solver_iterations"


def body_setting(index: int) -> dict[str, int]:
    """The ``MM_BODY`` override of grid point ``index`` (both probes' articulations)."""
    position, velocity = GRID[index]
    return {"solver_position_iterations": position, "solver_velocity_iterations": velocity}


def point_rows(index: int, truths: pd.DataFrame, noise_sigma: float, scan: dict[str, float]) -> pd.DataFrame:
    """One grid point's scan rows (``ex38_physx.scan_point``), tagged with its index and iteration counts."""
    rows = ex38_physx.scan_point({"body": body_setting(index)}, truths, noise_sigma, scan)
    cpu = rows.pop("cpu_s")
    position, velocity = GRID[index]
    return rows.assign(arm=ARM, value=float(index), position_iterations=position, velocity_iterations=velocity,
                       cpu_s=cpu)


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """E226's keys from the stored rows (the step and ``verify``): ex38's per-point and chosen-point keys (``p<i>.``,
    ``chosen.``, ``holds``; ``value`` is the grid index), with each point's and the chosen point's iteration counts."""
    out = ex38_physx.arm_keys(rows.drop(columns=["position_iterations", "velocity_iterations"]))
    counts = rows.groupby("value", sort=True)[["position_iterations", "velocity_iterations"]].first()
    for i, (value, row) in enumerate(counts.iterrows()):
        out[f"p{i}.position_iterations"] = int(row["position_iterations"])
        out[f"p{i}.velocity_iterations"] = int(row["velocity_iterations"])
        if "chosen.value" in out and out["chosen.value"] == value:
            out["chosen.position_iterations"] = int(row["position_iterations"])
            out["chosen.velocity_iterations"] = int(row["velocity_iterations"])
    return out


def sweep_rows(protocol: Any, indices: Iterable[int], count: int) -> pd.DataFrame:
    """The given grid points' rows on the first ``count`` development truths (0: all), each point in a process of
    its own (its PhysX scenes leave with it). Module-level over its points, so a pool may split them."""
    from probecommit.runner.aside import in_own_process

    truths = ex38_physx.development_truths(protocol, count)
    scan = dict(protocol.scan)
    return pd.concat([in_own_process(point_rows, int(i), truths, protocol.noise_sigma, scan) for i in indices],
                     ignore_index=True)


def run(job: Any) -> None:
    """The explain step (set aside; reads only the protocol): stored rows and keys. Skipped without SAPIEN."""
    import importlib.util

    count = int(job.cfg["ex40_truths_quick" if job.quick else "ex40_truths"])
    if count < 0 or importlib.util.find_spec("sapien") is None:
        return
    job.progress("explain: PhysX solver iteration sweep (E226)", 0, 1)
    rows = sweep_rows(job.p, QUICK if job.quick else range(len(GRID)), count)
    job.stored[STORED] = rows
    job.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "sweep_rows", "point_rows", "body_setting", "GRID", "QUICK", "STORED",
                          "GROUP")
