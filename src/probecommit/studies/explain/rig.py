"""The simulated rig redrawn: what the frozen rig design gives over fresh block positions (E33, E34).

Why: the paper's hardware claims (optimism intervals all covering zero; the boundary fault
resolving from 8 mm, coverage holding to 14 mm) are single sessions of 12 positions x 2
episodes per budget. Our simulated rig's one session differs; whether that is the design's
sampling or the rig is answered by running the same frozen protocol on fresh position draws
(only ``instances.seed`` changes) and reading the same statistics from each session.
Everything here is the simulated rig, never the physical arm.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_mean
from probecommit.robot.replay import fault_sweep
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import robot_table, session_episodes
from probecommit.runner.config import config_data, parse_config
from probecommit.studies.paper_values import value
from probecommit.studies.robot import BOUNDARY_SWEEP, boundary_holds_to, rig_config


def redrawn_sessions(runs: Path, seeds: list[int], quick: bool = False,
                     central: float | None = None, streams: bool = False,
                     positions: int | None = None) -> list[tuple[int, Path]]:
    """The frozen rig protocol run once per instance seed (block positions redrawn), logs under ``runs``; with
    ``central``, positions drawn within that fraction of the prior box's half-width (E225), clearance unchanged.

    ``streams``: the session seed also replaces the config's top ``seed``, which keys the tap locations, particles
    and misreads (E230; E33/E223/E225 hold them at the frozen session's); ``positions``: every session keeps the
    block positions of that instance seed (E231: ours, 7) while its streams are redrawn."""
    out = []
    for seed in seeds:
        data = config_data(rig_config(quick))
        data["instances"]["seed"] = int(seed if positions is None else positions)
        if streams or positions is not None:
            data["seed"] = int(seed)
        if central is not None:
            low, high = list(data["model"]["prior_low"]), list(data["model"]["prior_high"])
            data["instances"]["truth_low"] = [low[0] * central, *low[1:]]
            data["instances"]["truth_high"] = [high[0] * central, *high[1:]]
        tag = ("central_" if central is not None else "") + ("streams_" if streams else "") + (
            f"positions{positions}_" if positions is not None else "")
        path = runs / f"rig_redraw_{tag}{seed}"
        simulate_session(path, parse_config(data))
        out.append((seed, path))
    return out


#: The stored rows (``explain/results/``): every redrawn session's episodes (the columns Table IX reads) and each
#: session's boundary sweep summary; ``optimism_summary`` and ``boundary_summary`` read them (explain and verify).
STORED_SESSIONS = "rig_redraws_sessions.parquet"
#: The rig table's budgets (taps); T26 tests an interval and a bound at each.
BUDGET_TAPS = (1, 2, 3, 4, 5)
STORED_BOUNDARY = "rig_redraws_boundary.parquet"
#: E225's sessions, positions drawn in the central part of the prior box (``rig_redraws_central`` of explain.yaml).
STORED_CENTRAL = "rig_redraws_central_sessions.parquet"
#: E230's sessions, every stream redrawn with the positions (``rig.yaml``'s top seed = the session's seed).
STORED_STREAMS = "rig_redraws_streams_sessions.parquet"
#: E231's sessions, our positions (``instances.seed`` of ``rig.yaml``) with the streams redrawn.
STORED_OWN_POSITIONS = "rig_redraws_own_positions_sessions.parquet"
#: E234's sessions: E230's design on seeds never used before (``rig_confirm_seed``, ``rig_confirm`` of explain.yaml).
STORED_CONFIRM = "rig_redraws_confirm_sessions.parquet"
#: The stored session sets beside E223's, by the key group each fills (``keys``; verify reads those present).
VARIANTS = {"central": STORED_CENTRAL, "streams": STORED_STREAMS, "own_positions": STORED_OWN_POSITIONS,
            "confirm": STORED_CONFIRM}
SESSION_COLUMNS = ("session", "instance_id", "k", "predicted", "realized", "covered", "escaped", "entered", "aim_error")


def session_rows(sessions: list[tuple[int, Path]]) -> pd.DataFrame:
    """Every session's episode rows (``SESSION_COLUMNS``), sessions in order."""
    rows = [session_episodes(path).rows.assign(session=seed) for seed, path in sessions]
    pooled = pd.concat(rows, ignore_index=True)
    return pooled[[c for c in SESSION_COLUMNS if c in pooled]]


def optimism_redraws(sessions: list[tuple[int, Path]], boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame]:
    """Per session, which budgets' optimism intervals exclude zero; pooled over sessions, optimism per budget."""
    return optimism_summary(session_rows(sessions), boot)


def optimism_summary(pooled: pd.DataFrame, boot: dict[str, Any]) -> tuple[dict[str, Any], pd.DataFrame]:
    """``optimism_redraws`` from the sessions' stored rows: each session's Table IX optimism intervals, the
    shares excluding zero, and the pooled optimism per budget (clusters: session and position)."""
    tables = []
    for seed, ep in pooled.groupby("session", sort=False):
        t = robot_table(ep.reset_index(drop=True), **boot).assign(session=seed)
        tables.append(t[["session", "taps", "optimism", "optimism_lo", "optimism_hi"]])
    table = pd.concat(tables, ignore_index=True)
    table["excludes_zero"] = (table["optimism_lo"] > 0) | (table["optimism_hi"] < 0)
    table["outside_bound"] = table["optimism"].abs() > value("T26-hardware-optimism.bound") + 1e-12
    per_session = table.groupby("session")[["excludes_zero", "outside_bound"]].sum()
    out: dict[str, Any] = {"sessions": int(pooled["session"].nunique()),
                           "share_sessions_any_interval_excluding_zero": float((per_session["excludes_zero"] >= 1).mean()),
                           "share_sessions_two_or_more_excluding_zero": float((per_session["excludes_zero"] >= 2).mean()),
                           "share_intervals_excluding_zero": float(table["excludes_zero"].mean()),
                           # E223: the paper's whole sentence on one session (every interval covers zero, every
                           # budget's optimism within its bound), as a share of the redrawn sessions.
                           "share_sessions_paper_outcome": float(((per_session["excludes_zero"] == 0)
                                                                  & (per_session["outside_bound"] == 0)).mean())}
    # E223's other side (rev2): how many sessions fail at least j of T26's ten labels, to rank our own session.
    failing = (per_session["excludes_zero"] + per_session["outside_bound"]).to_numpy()
    out.update({f"sessions_failing_at_least.{j}": int((failing >= j).sum()) for j in range(2 * len(BUDGET_TAPS) + 1)})
    pooled = pooled.assign(cluster=pooled["session"].astype(str) + "/" + pooled["instance_id"].astype(str))
    worst = 0.0
    for k, g in pooled.groupby("k", sort=True):
        iv = cluster_bootstrap_mean((g["realized"] - g["predicted"]).to_numpy(float), g["cluster"].to_numpy(), **boot)
        out[f"pooled_optimism.k{int(k)}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
        worst = max(worst, abs(float(iv.estimate)))
    out["pooled_optimism.max_abs"] = worst
    return out, table


def boundary_rows(sessions: list[tuple[int, Path]], boot: dict[str, Any], sizes: list[float]) -> pd.DataFrame:
    """Per session, the boundary fault's first resolved size (NaN: never) and the size coverage holds to."""
    rows = []
    for seed, path in sessions:
        sweep, _ = fault_sweep(path, "boundary", sizes, **boot)
        resolved = sweep[sweep["optimism_resolved"].astype(bool) & (sweep["size"] > 0)]
        rows.append({"session": int(seed), "first_resolved_mm": float(resolved["size"].min()) if len(resolved) else float("nan"),
                     "holds_to_mm": float(boundary_holds_to(sweep)), "sweep_end_mm": float(max(sizes))})
    return pd.DataFrame(rows, columns=["session", "first_resolved_mm", "holds_to_mm", "sweep_end_mm"])


def boundary_redraws(sessions: list[tuple[int, Path]], boot: dict[str, Any], sizes: list[float]) -> dict[str, Any]:
    """Per session, the boundary fault's first resolved size and the size coverage holds to; their spread."""
    return boundary_summary(boundary_rows(sessions, boot, sizes))


def boundary_summary(rows: pd.DataFrame) -> dict[str, Any]:
    """``boundary_redraws`` from the per-session rows: the share never resolved, and the spread of each size."""
    f, h = rows["first_resolved_mm"].to_numpy(float), rows["holds_to_mm"].to_numpy(float)
    out: dict[str, Any] = {"sessions": len(rows), "share_never_resolved": float(np.mean(np.isnan(f)))}
    for name, v in (("first_resolved_mm", f[~np.isnan(f)]), ("coverage_holds_to_mm", h)):
        if len(v):
            out[f"{name}.median"] = float(np.median(v))
            out[f"{name}.p025"], out[f"{name}.p975"] = (float(x) for x in np.percentile(v, [2.5, 97.5]))
            out[f"{name}.min"], out[f"{name}.max"] = float(v.min()), float(v.max())
    out["coverage_holds_to_mm.share_at_sweep_end"] = float(np.mean(h >= float(rows["sweep_end_mm"].iloc[0])))
    return out


def keys(sessions: pd.DataFrame, boundary: pd.DataFrame, boot: dict[str, Any],
         variants: dict[str, pd.DataFrame] | None = None) -> dict[str, Any]:
    """Keys of ``explain:results.rig_redraws`` from the stored rows (the explain step and verify both call this);
    ``variants``: the other session sets by group (``VARIANTS``: E225's ``central``, E230's ``streams``, E231's
    ``own_positions``, E234's ``confirm``), each under ``<group>.optimism.``."""
    opt, _ = optimism_summary(sessions, boot)
    out = {f"optimism.{k}": v for k, v in opt.items()}
    out.update({f"boundary.{k}": v for k, v in boundary_summary(boundary).items()})
    for group, rows in (variants or {}).items():
        out.update({f"{group}.optimism.{k}": v for k, v in optimism_summary(rows, boot)[0].items()})
    return out


def confirm_seeds(cfg: dict[str, Any], quick: bool) -> list[int]:
    """E234's session seeds: E230's design confirmed on seeds no other run uses (declared before they ran)."""
    count = int(cfg["rig_confirm_quick" if quick else "rig_confirm"])
    return [int(cfg["rig_confirm_seed"]) + i for i in range(count)]


def run(runs: Path, cfg: dict[str, Any], boot: dict[str, Any], quick: bool) -> tuple[dict[str, Any], dict[str, pd.DataFrame]]:
    """Every redraw experiment: the keys of ``explain:results.rig_redraws`` and the stored rows by file name."""
    count = int(cfg["rig_redraws_quick" if quick else "rig_redraws"])
    seeds = [int(cfg["rig_redraw_seed"]) + i for i in range(count)]
    sessions = redrawn_sessions(runs, seeds, quick)
    sizes = BOUNDARY_SWEEP[::7] if quick else BOUNDARY_SWEEP
    own = int(config_data(rig_config(quick))["instances"]["seed"])
    variants = {"central": session_rows(redrawn_sessions(runs, seeds, quick, float(cfg["rig_redraws_central"]))),
                "streams": session_rows(redrawn_sessions(runs, seeds, quick, streams=True)),
                "own_positions": session_rows(redrawn_sessions(runs, seeds, quick, positions=own)),
                "confirm": session_rows(redrawn_sessions(runs, confirm_seeds(cfg, quick), quick, streams=True))}
    tables = {STORED_SESSIONS: session_rows(sessions), STORED_BOUNDARY: boundary_rows(sessions, boot, sizes),
              **{VARIANTS[group]: rows for group, rows in variants.items()}}
    return keys(tables[STORED_SESSIONS], tables[STORED_BOUNDARY], boot, variants), tables
