"""Cross-engine insertion study (paper Sec. V-C, "Across engines", Table VIII).

Plain functions over simulator objects (anything with the insertion simulator's named
queries ``tap_reading(x_hole, c, u)`` and ``peg_depth(x_hole, c, a)``, in mm):

* :func:`check_engines`: the same hand queries on every engine, against the scene's
  designed answer, with an ``agree`` flag per query;
* :func:`scan_boundary`: each engine's pocket-reading boundary ``hg + delta`` (grid then
  bisection on both sides of each truth; the MuJoCo scan of :mod:`.scan`, engine-agnostic);
* :func:`scan_capture_window`: each engine's capture half-width against ``w(c) = 0.6 c + 1.1``;
* :func:`table_variants` / :func:`engines_table`: Table VIII's three tap models per engine
  (deployed, MuJoCo offset not refitted, the engine's own scan) and its layout from
  per-(engine, variant) audit tables.

Simulators are passed in, never built here, except that :func:`check_engines` accepts an
engine name as a convenience (:func:`make_simulator`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from probecommit.studies.scan import ScanResult, boundary_scan
from probecommit.tasks.insertion.model import (
    PAPER_DELTA_MM,
    POCKET_DEPTH_MM,
    TIP_RADIUS_MM,
    capture_half_width,
    half_gap,
)
from probecommit.tasks.insertion.sim_base import ENTRY_DEPTH_FRACTION
from probecommit.tasks.insertion.sim_mujoco import CHAMFER_MM  # the reference scene (needs no mujoco)

#: ``"module:Class"`` of each engine's insertion simulator (built lazily by name).
SIMULATORS = {
    "mujoco": "probecommit.tasks.insertion.sim_mujoco:MujocoInsertionSimulator",
    "pybullet": "probecommit.tasks.insertion.sim_pybullet:PybulletInsertionSimulator",
    "sapien": "probecommit.tasks.insertion.sim_sapien:SapienInsertionSimulator",
    "analytic": "probecommit.tasks.insertion.sim_base:AnalyticInsertionSimulator",
}

#: A check reading or depth agrees when within this of the expected value (mm): the tap
#: noise sigma. Top/floor and entered/resting differ by 15 mm, so this is unambiguous.
CHECK_TOLERANCE_MM = 0.5

def make_simulator(engine: str, **kwargs: Any) -> Any:
    """Build an engine's insertion simulator by name (lazy import of the engine).

    Args:
        engine: A key of :data:`SIMULATORS`.
        **kwargs: Passed to the simulator's constructor.
    """
    import importlib

    if engine not in SIMULATORS:
        raise ValueError(f"unknown engine {engine!r}; choose from {sorted(SIMULATORS)}")
    module, cls = SIMULATORS[engine].split(":")
    return getattr(importlib.import_module(module), cls)(**kwargs)


def _ask(simulator: Any, kind: str, x_hole: float, c: float, arg: float) -> float:
    """One named query, through the simulator's cache when it has one."""
    if hasattr(simulator, "query"):
        return float(simulator.query(kind, x_hole, c, arg))
    return float(getattr(simulator, kind)(float(x_hole), float(c), float(arg)))


def default_check_queries(x_hole: float = 0.0, c: float = 1.0) -> pd.DataFrame:
    """The hand queries of the engine check, for one instance, with the designed answers.

    The expected answers are the scene's design: a tap reads the floor (-15 mm) inside the
    chamfer's outer edge ``hg + CHAMFER_MM`` (the tip slides down the chamfer) and the
    plate top (0) beyond; a peg enters (15 mm) within ``w(c)`` and rests on top (0) beyond.
    ``deployed_model`` is what the analytic model as deployed (boundary ``hg - r``) says.

    Args:
        x_hole: Slot centre (mm).
        c: Clearance scale.

    Returns:
        Columns ``query, kind, x_hole, c, arg, expected, deployed_model``.
    """
    hg, w = float(half_gap(c)), float(capture_half_width(c))
    floor, depth = -POCKET_DEPTH_MM, POCKET_DEPTH_MM
    rows = [
        ("tap over the plate", "tap_reading", x_hole + hg + 5.0, 0.0),
        ("tap over the slot centre", "tap_reading", x_hole, floor),
        ("tap on the chamfer", "tap_reading", x_hole + hg + 0.5 * CHAMFER_MM, floor),
        ("peg centred", "peg_depth", x_hole, depth),
        ("peg 1 mm off", "peg_depth", x_hole + 1.0, depth if 1.0 < w else 0.0),
        ("peg 3 mm off", "peg_depth", x_hole + 3.0, depth if 3.0 < w else 0.0),
    ]
    out = pd.DataFrame(rows, columns=["query", "kind", "arg", "expected"])
    out.insert(2, "x_hole", float(x_hole))
    out.insert(3, "c", float(c))
    off = np.abs(out["arg"] - x_hole)
    out["deployed_model"] = np.where(
        out["kind"] == "tap_reading",
        np.where(off < hg - TIP_RADIUS_MM, floor, 0.0),
        np.where(off < w, depth, 0.0))
    return out


def check_engines(engines: Mapping[str, Any] | Iterable[Any], queries: pd.DataFrame | None = None,
                  tolerance: float = CHECK_TOLERANCE_MM) -> pd.DataFrame:
    """Run the same hand queries on every engine and flag disagreement with the design.

    Args:
        engines: ``{name: simulator}``, or simulators (named by their ``engine``
            attribute), or engine names (built with :func:`make_simulator`). Passing a
            simulator is how a test plants a disagreement.
        queries: Columns ``query, kind, x_hole, c, arg, expected`` (default:
            :func:`default_check_queries` at ``x_hole = 0, c = 1``).
        tolerance: Largest ``|value - expected|`` (mm) that agrees.

    Returns:
        One row per query: the query columns, one value column per engine, ``agree``
        (every engine within ``tolerance``) and ``disagreeing`` (comma-separated engine
        names). ``attrs["tolerance"]`` holds the tolerance.
    """
    if isinstance(engines, Mapping):
        sims = dict(engines)
    else:
        sims = {}
        for e in engines:
            sim = make_simulator(e) if isinstance(e, str) else e
            name = e if isinstance(e, str) else str(getattr(sim, "engine", type(sim).__name__))
            if name in sims:
                raise ValueError(f"engine {name!r} given twice; pass a dict to name them apart")
            sims[name] = sim
    if not sims:
        raise ValueError("check_engines needs at least one engine")
    table = (default_check_queries() if queries is None else queries).copy().reset_index(drop=True)
    bad = np.zeros(len(table), dtype=bool)
    who: list[list[str]] = [[] for _ in range(len(table))]
    for name, sim in sims.items():
        values = np.array([_ask(sim, r.kind, r.x_hole, r.c, r.arg) for r in table.itertuples()])
        table[name] = values
        off = ~(np.abs(values - table["expected"].to_numpy()) <= tolerance)  # NaN disagrees
        bad |= off
        for i in np.flatnonzero(off):
            who[i].append(name)
    table["agree"] = ~bad
    table["disagreeing"] = [", ".join(w) for w in who]
    table.attrs["tolerance"] = float(tolerance)
    return table


def _truth_frame(truths: pd.DataFrame | Iterable[tuple[float, float]]) -> pd.DataFrame:
    """Truths as ``instance_id, true_x_hole, true_c`` (accepts (x_hole, c) pairs)."""
    if isinstance(truths, pd.DataFrame):
        missing = {"true_x_hole", "true_c"} - set(truths.columns)
        if missing:
            raise ValueError(f"truths lack columns {sorted(missing)}")
        out = truths.copy()
        if "instance_id" not in out.columns:
            out["instance_id"] = [f"t{i}" for i in range(len(out))]
        return out.reset_index(drop=True)
    pairs = [(float(x), float(c)) for x, c in truths]
    return pd.DataFrame({"instance_id": [f"t{i}" for i in range(len(pairs))],
                         "true_x_hole": [p[0] for p in pairs], "true_c": [p[1] for p in pairs]})


def scan_boundary(simulator: Any, truths: pd.DataFrame | Iterable[tuple[float, float]], step: float = 0.25,
                  half_range: float = 7.0, tolerance: float = 1e-3) -> ScanResult:
    """The engine's pocket-reading boundary offset ``delta`` (boundary minus ``hg``).

    For each truth the tap reading is sampled on a grid of lateral offsets from the hole
    (``step`` over ``+-half_range``), then each side's outermost pocket-to-top flip is
    bisected to ``tolerance`` (the paper's protocol; :func:`.scan.boundary_scan`).

    Args:
        simulator: Any insertion simulator (``query`` or ``tap_reading``).
        truths: Columns ``true_x_hole, true_c`` (and ``instance_id``), or (x_hole, c) pairs.
        step, half_range, tolerance: Grid step, grid half-range and bisection tolerance (mm).

    Returns:
        The :class:`.scan.ScanResult`: ``scans`` has one row per truth and side with
        ``offset`` = boundary - hg; ``summary()`` gives mean (``delta``), SD, min, max.
    """
    if not hasattr(simulator, "query"):
        simulator = _Queryable(simulator)
    return boundary_scan(simulator, _truth_frame(truths), step, half_range, tolerance)


class _Queryable:
    """Adapter giving a bare simulator (named queries only) the ``query`` entry point."""

    #: The declared Simulator attribute the scans read: a bare simulator answers one query at a time.
    parallel_queries = False

    def __init__(self, sim: Any) -> None:
        self.sim = sim

    def query(self, kind: str, x_hole: float, c: float, arg: float) -> float:
        return float(getattr(self.sim, kind)(float(x_hole), float(c), float(arg)))


@dataclass
class CaptureResult:
    """Capture-window scans: per side and per truth, and the ratio to ``w(c)``."""

    sides: pd.DataFrame  # instance_id, x_hole, c, side, half_width, enters_beyond
    truths: pd.DataFrame  # instance_id, x_hole, c, w, window (mean of the sides), ratio

    def summary(self) -> dict[str, float]:
        """Mean, SD (ddof 1), min and max of the per-truth ratio window / w(c)."""
        r = self.truths["ratio"]
        return {"ratio_mean": float(r.mean()), "ratio_sd": float(r.std(ddof=1)) if len(r) > 1 else 0.0,
                "ratio_min": float(r.min()), "ratio_max": float(r.max()), "truths": int(len(r)),
                "sides_entering_beyond": int(self.sides["enters_beyond"].sum())}


def scan_capture_window(simulator: Any, truths: pd.DataFrame | Iterable[tuple[float, float]], step: float = 0.25,
                        half_range: float = 7.0, tolerance: float = 1e-3, check_beyond: bool = True) -> CaptureResult:
    """The engine's capture half-width: the largest ``|a - x_hole|`` at which the peg enters.

    Entry is the paper's outcome rule: the peg reaches at least 60% of the pocket depth.
    Per truth and side, aims step outward from the hole centre by ``step`` until the
    first that fails, then the last entering / first failing pair is bisected to
    ``tolerance``: the window is the contiguous entering interval around the hole. A peg
    that fails even centred has window 0 on both sides. With ``check_beyond`` the rest of
    the grid out to ``half_range`` is tried too and ``enters_beyond`` flags a side where
    some farther aim enters again (a snag, not a wider window). The per-truth window is
    the mean of its two sides, and its ratio is to ``w(c) = 0.6 c + 1.1``.

    Args:
        simulator: Any insertion simulator (``query`` or ``peg_depth``).
        truths: Columns ``true_x_hole, true_c`` (and ``instance_id``), or (x_hole, c) pairs.
        step, half_range, tolerance: Outward step, largest offset tried and bisection
            tolerance (mm).
        check_beyond: Also try every grid aim past the first failure.

    Returns:
        A :class:`CaptureResult`.
    """
    entry = ENTRY_DEPTH_FRACTION * POCKET_DEPTH_MM
    side_rows, truth_rows = [], []
    for inst in _truth_frame(truths).itertuples():
        x, c = float(inst.true_x_hole), float(inst.true_c)

        def enters(a: float) -> bool:
            return _ask(simulator, "peg_depth", x, c, a) >= entry

        widths = []
        for side, sgn in (("left", -1.0), ("right", 1.0)):
            beyond = False
            if not enters(x):
                width, outer = 0.0, 0.0
            else:
                inner, outer = 0.0, step
                while enters(x + sgn * outer):
                    inner, outer = outer, outer + step
                    if outer > half_range + 1e-9:
                        raise RuntimeError(f"capture of x_hole={x:.3f}, c={c:.3f}: peg enters out to +-{half_range} mm")
                first_fail = outer
                while outer - inner > tolerance:
                    mid = 0.5 * (inner + outer)
                    inner, outer = (mid, outer) if enters(x + sgn * mid) else (inner, mid)
                width, outer = 0.5 * (inner + outer), first_fail
            if check_beyond:
                # Does any grid aim past the first failure enter again (a non-contiguous window)?
                grid = np.arange(outer + step, half_range + 1e-9, step)
                beyond = any(enters(x + sgn * o) for o in grid)
            widths.append(width)
            side_rows.append({"instance_id": inst.instance_id, "x_hole": x, "c": c, "side": side, "half_width": width,
                              "enters_beyond": beyond})
        w = float(capture_half_width(c))
        window = float(np.mean(widths))
        truth_rows.append({"instance_id": inst.instance_id, "x_hole": x, "c": c, "w": w, "window": window,
                           "ratio": window / w})
    return CaptureResult(pd.DataFrame(side_rows), pd.DataFrame(truth_rows))


# --------------------------------------------------------------------------- Table VIII
#: Table VIII's rows: (label, audit_table column).
TABLE_ROWS = (("support escape", "escape"), ("episode coverage", "coverage"),
              ("optimism e_k", "optimism"), ("failure", "realized"))
#: Table VIII's columns per engine, in order.
TABLE_VARIANTS = ("deployed", "mj_offset", "own_scan")


def scan_rows(engine: str, boundary: Any, capture: CaptureResult) -> pd.DataFrame:
    """One engine's scans as one table (``kind``: ``boundary``, ``capture`` per truth, ``capture_side``),
    what a publication stores (``engine_scans.parquet``) and :func:`scan_summaries` reads."""
    sides = capture.sides.assign(enters_beyond=capture.sides["enters_beyond"].astype(float))
    return pd.concat([boundary.scans.assign(kind="boundary"), capture.truths.assign(kind="capture"),
                      sides.assign(kind="capture_side")], ignore_index=True).assign(engine=engine)


def scan_summaries(rows: pd.DataFrame) -> dict[str, dict[str, dict[str, float]]]:
    """Per engine, the boundary scan's and the capture scan's summaries from the stored scan rows (one function
    for the study and for ``probecommit verify``)."""
    from probecommit.studies.scan import ScanResult

    out = {}
    for engine, part in rows.groupby("engine", sort=False):
        kind = lambda name: part[part["kind"] == name].reset_index(drop=True)  # noqa: E731
        out[engine] = {"boundary": ScanResult(kind("boundary"), pd.DataFrame()).summary(),
                       "capture": CaptureResult(kind("capture_side"), kind("capture")).summary()}
    return out


def table_variants(own_delta: float, mujoco_delta: float = PAPER_DELTA_MM) -> dict[str, float]:
    """The three tap-boundary offsets Table VIII runs in one engine.

    Args:
        own_delta: The engine's own scanned offset (:func:`scan_boundary`'s ``delta``).
        mujoco_delta: The MuJoCo-fitted offset, applied *not refitted*.

    Returns:
        ``{"deployed": -r, "mj_offset": mujoco_delta, "own_scan": own_delta}`` for
        ``InsertionModel(boundary_offset=...)``.
    """
    return {"deployed": -TIP_RADIUS_MM, "mj_offset": float(mujoco_delta), "own_scan": float(own_delta)}


def engines_table(audits: Mapping[tuple[str, str], pd.DataFrame], k: int = 8,
                  method: str | None = None) -> pd.DataFrame:
    """Table VIII's layout from audit tables, one per (engine, variant).

    Args:
        audits: ``{(engine, variant): audit_table(...)}`` (see
            :func:`probecommit.audit.metrics.audit_table`), variants from
            :data:`TABLE_VARIANTS`.
        k: The budget reported (the paper: random probes, ``k = 8``).
        method: Keep only this ``method`` when the audit tables have several.

    Returns:
        Rows ``support escape, episode coverage, optimism e_k, failure``; columns a
        MultiIndex ``(engine, variant)`` in the order given.
    """
    cols, data = [], []
    for (engine, variant), audit in audits.items():
        rows = audit.loc[audit["k"] == k]
        if method is not None and "method" in rows.columns:
            rows = rows.loc[rows["method"] == method]
        if len(rows) != 1:
            raise ValueError(f"{engine}/{variant}: expected one audit row at k={k}, found {len(rows)}")
        cols.append((engine, variant))
        data.append([float(rows[col].iloc[0]) for _, col in TABLE_ROWS])
    return pd.DataFrame(np.array(data).T, index=[label for label, _ in TABLE_ROWS],
                        columns=pd.MultiIndex.from_tuples(cols, names=["engine", "variant"]))


# ----------------------------------------------------------------------------- the study


#: The episode columns Table VIII, the escape curves and the paired differences read (stored compactly).
ENGINE_EPISODE_COLUMNS = ("instance_id", "repeat", "k", "method", "status", "predicted", "realized", "covered",
                          "escaped", "score_s")


def summarize_engine_runs(episodes: pd.DataFrame, resamples: int, seed: int) -> tuple[pd.DataFrame, list[dict], pd.DataFrame]:
    """Table VIII, the paired failure differences at k = 8 and escape against k, from the episodes of
    every (engine, variant) run (columns ``engine``, ``variant``). ``verify`` calls it on the stored table."""
    from probecommit.audit.metrics import audit_table
    from probecommit.audit.stats import paired_bootstrap

    boot = dict(resamples=resamples, seed=seed)
    audits: dict[tuple[str, str], pd.DataFrame] = {}
    paired_rows: list[dict] = []
    escape_rows: list[dict] = []
    for (engine, variant), part in episodes.groupby(["engine", "variant"], sort=False):
        part = part.drop(columns=["engine", "variant"]).reset_index(drop=True)
        audits[(engine, variant)] = audit_table(part[part["method"] == "probe_robust"], **boot)
        per_k = part[(part["method"] == "probe_robust") & (part["status"] == "ok")].groupby("k")["escaped"].mean()
        escape_rows += [{"engine": engine, "variant": variant, "k": int(k), "escape": float(v)} for k, v in per_k.items()]
    final = episodes[(episodes["method"] == "probe_robust") & (episodes["k"] == 8)]
    for engine, part in final.groupby("engine", sort=False):
        b = part[part["variant"] == "deployed"].drop(columns=["engine", "variant"]).reset_index(drop=True)
        for variant in ("mj_offset", "own_scan"):
            t = part[part["variant"] == variant].drop(columns=["engine", "variant"]).reset_index(drop=True)
            diff = paired_bootstrap(b, t, "realized", **boot).difference
            paired_rows.append({"engine": engine, "variant": variant,
                                "failure_difference": [diff.estimate, diff.lo, diff.hi]})
    return engines_table(audits, k=8), paired_rows, pd.DataFrame(escape_rows)


def run_engine_study(protocol: Any, root: str | Path, engines: Iterable[str] = ("pybullet", "sapien"), *,
                     workers: int = 1, progress: Any = None) -> dict[str, Any]:
    """Table VIII and the scene properties of the insertion scene in each engine.

    Per engine: the tap-boundary scan and the capture-window scan on the development
    truths; one random-probe run of the Split B test instances (k = 1..8) with the
    deployed model; replays of the same taps with the MuJoCo-fitted offset (not
    refitted) and with the engine's own scanned offset; the audit of each (k = 8),
    the paired failure differences against the deployed model, and escape against k.

    Args:
        protocol: The insertion protocol (``studies.protocol.Protocol``).
        root: Folder for run directories (``<root>/<engine>_B_test_random``, ...).
        engines: Engines to study.
        workers: Local worker processes for the runs.
        progress: ``progress(step, done, total)``.

    Returns:
        ``{"table": DataFrame, "paired": [...], "escape": DataFrame, "scans": {engine: {...}}}``.
    """
    from pathlib import Path as _Path

    from probecommit.runner.build import build_model
    from probecommit.runner.config import config_data, parse_config
    from probecommit.runner.instances import draw_instances
    from probecommit.runner.replay import load_run, replay_run
    from probecommit.runner.study import run_study
    from probecommit.store.rundir import RunDir

    root = _Path(root)
    step = progress or (lambda *a: None)
    boot = dict(resamples=protocol.bootstrap.resamples, seed=protocol.bootstrap.seed)
    dev_config = protocol.run_config("development", "development", "development", "random")
    dev = draw_instances(dev_config, build_model(dev_config))
    stored: list[pd.DataFrame] = []
    scans: dict[str, Any] = {}
    scan_tables: list[pd.DataFrame] = []
    for engine in engines:
        sim = make_simulator(engine, noise_sigma=protocol.noise_sigma)
        step(f"{engine}: boundary scan", 0, 1)
        boundary = scan_boundary(sim, dev, protocol.scan["step"], protocol.scan["half_range"], protocol.scan["tolerance"])
        step(f"{engine}: capture-window scan", 0, 1)
        capture = scan_capture_window(sim, dev)
        rows = scan_rows(engine, boundary, capture)
        scan_tables.append(rows)
        scans[engine] = {**scan_summaries(rows)[engine], "engine_calls": dict(sim.engine_calls)}
        own = scans[engine]["boundary"]["delta"]
        base_cfg = protocol.run_config(f"{engine}_B_test_random", "B", "B_test", "random")
        data = config_data(base_cfg)
        data["simulator"] = {**data["simulator"], "engine": engine}
        base = run_study(parse_config(data), root / f"{engine}_B_test_random", workers=workers,
                         progress=lambda d, t: step(f"{engine}: run", d, t))
        runs = {"deployed": load_run(base.run_dir)}
        for variant, delta in (("mj_offset", PAPER_DELTA_MM), ("own_scan", own)):
            path = root / f"{engine}_B_test_random_{variant}"
            if not RunDir(path).is_complete():
                replay_run(base.run_dir, path, {"model": {"boundary": "corrected", "delta": float(delta)}})
            runs[variant] = load_run(path)
        for variant, loaded in runs.items():
            stored.append(loaded.episodes[[c for c in ENGINE_EPISODE_COLUMNS if c in loaded.episodes.columns]]
                          .assign(engine=engine, variant=variant))
    episodes = pd.concat(stored, ignore_index=True)
    table, paired_rows, escape = summarize_engine_runs(episodes, **boot)
    return {"table": table, "paired": paired_rows, "escape": escape, "scans": scans, "episodes": episodes,
            "scan_rows": pd.concat(scan_tables, ignore_index=True),
            "bootstrap": boot}
