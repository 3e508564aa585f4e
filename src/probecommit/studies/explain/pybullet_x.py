"""PyBullet's escape at k = 8 under the scene properties the paper reports for PyBullet (E45).

Why: the paper's PyBullet escape climbs to 0.167 at k = 8; ours reaches 0.109. The paper
prints two PyBullet scene properties (Sec. V-C): the tap boundary at hg + 0.929 mm and a
capture window 1.21 x w(c), with SD 0.69 of that ratio over the 24 development truths. This
step runs the analytic scene given exactly those two properties on the engines study's own
instances and probe streams (its run config, only the simulator changed), so that:

* its escape says whether PyBullet's reported boundary gives the paper's escape on our draw;
* a second run with the model's capture window (scale 1) on the same streams says whether the
  capture window moves escape at all (the tap reading does not read the capture window, so a
  per-truth spread of it cannot either: each truth's readings are those of the scale-1 run);
* the per-truth spread is emulated on the aims, each instance's capture scale drawn from a
  gamma law with the paper's mean and SD (seeded), for the failure it would give;
* the stored PyBullet run's escape at each budget is read beside them.

No frozen config is changed; the runs live under ``explain/runs``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.stats import cluster_bootstrap_mean
from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import LoadedRun, load_run
from probecommit.runner.study import run_study
from probecommit.studies.explain.stats import capture_failure
from probecommit.studies.paper_values import value


def gamma_scales(mean: float, sd: float, n: int, seed: int) -> np.ndarray:
    """``n`` positive capture scales with the given mean and SD (a gamma law: shape (mean/sd)^2)."""
    shape = (mean / sd) ** 2
    return np.random.default_rng(seed).gamma(shape, mean / shape, size=n)


def _emulated(source: LoadedRun, runs: Path, name: str, offset: float, scale: float, workers: int,
              split: str | None = None) -> LoadedRun:
    data = config_data(source.config)
    data["name"] = name
    if split is not None:
        data["instances"] = {**data["instances"], "split": split}
    data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": float(offset),
                         "capture_scale": float(scale)}
    path = runs / name
    run_study(parse_config(data), path, workers=workers, threads=1)
    return load_run(path)


def _probe_k(episodes: Any, k: int | None) -> Any:
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    return rows if k is None else rows[rows["k"] == k]


def draw_range(values: list[float]) -> dict[str, float]:
    """Mean, SD, min, max and the 2.5 / 97.5 % points (linear interpolation) of per-draw values."""
    v = np.asarray(values, dtype=float)
    return {"count": int(v.size), "mean": float(v.mean()), "sd": float(v.std(ddof=1)) if v.size > 1 else 0.0,
            "min": float(v.min()), "max": float(v.max()), "p025": float(np.quantile(v, 0.025)),
            "p975": float(np.quantile(v, 0.975))}


#: The stored per-draw escapes (``explain/results/``): what the draws' spread is computed from.
STORED = "pybullet_draws.parquet"


def stored_keys(deployed: Any, draws: Any, kmax: int, boot: dict[str, Any]) -> dict[str, Any]:
    """``stored.escape_k{1,kmax}`` (the engines study's PyBullet B_test_random rows) and ``draws.escape_k8.*``
    (the per-draw escapes, ``STORED``): the explain step and ``verify`` both call this."""
    out: dict[str, Any] = {}
    for k in (1, kmax):
        rows = _probe_k(deployed, k)
        iv = cluster_bootstrap_mean(rows["escaped"].to_numpy(float), rows["instance_id"].to_numpy(), **boot)
        out[f"stored.escape_k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    if len(draws):
        out.update({f"draws.escape_k8.{k}": v for k, v in draw_range(list(draws["escape_k8"])).items()})
    return out


#: The emulated scene's stored rows: ``part`` ``paper`` / ``unit`` (the paper's capture window / the model's) Probe-Robust
#: rows at every budget, and ``paper_probe`` / ``unit_probe`` (each tap's reading, in the runs' probe order).
EMULATED = "pybullet_emulated_episodes.parquet"
EMULATED_COLUMNS = ("instance_id", "repeat", "k", "action", "z_true", "predicted", "escaped", "true_c", "instance_index",
                    "instances")


def emulated_rows(paper: LoadedRun, unit: LoadedRun) -> pd.DataFrame:
    """The stored rows of both emulated scenes (``EMULATED``): what :func:`emulated_keys` reads."""
    parts = []
    for name, run in (("paper", paper), ("unit", unit)):
        inst = run.instances.reset_index(drop=True)
        index = dict(zip(inst["instance_id"], inst.index))
        rows = _probe_k(run.episodes, None)
        rows = rows.assign(true_c=inst.set_index("instance_id").loc[rows["instance_id"], "true_c"].to_numpy(float),
                           instance_index=rows["instance_id"].map(index).astype("int32"), instances=len(inst))
        parts.append(rows[list(EMULATED_COLUMNS)].assign(part=name))
        parts.append(pd.DataFrame({"part": f"{name}_probe", "y": np.asarray(run.probes["y"].to_numpy(), float)}))
    return pd.concat(parts, ignore_index=True)


def emulated_keys(rows: pd.DataFrame, stored: pd.DataFrame, kmax: int, boot: dict[str, Any], seed: int = 0) -> dict[str, Any]:
    """``pybullet_escape``'s emulated-scene keys from the stored rows (``emulated_rows``) and the engines study's
    PyBullet episodes (``stored``: the run's, or its rows in ``engine_episodes.parquet`` in verify)."""
    part = lambda name: rows[rows["part"] == name].drop(columns="part").reset_index(drop=True)  # noqa: E731
    paper, unit = part("paper"), part("unit")
    ratio, sd = value("T18-engine-scans.pybullet_ratio"), value("T18-engine-scans.pybullet_ratio_sd")
    out: dict[str, Any] = {}
    for k in (1, kmax):
        at = paper[paper["k"] == k]
        iv = cluster_bootstrap_mean(at["escaped"].to_numpy(float), at["instance_id"].to_numpy(), **boot)
        out[f"emulated.escape_k{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
    out["capture_moves_readings"] = int(not bool((part("paper_probe")["y"].to_numpy() == part("unit_probe")["y"].to_numpy()).all()))
    e_paper, e_unit = paper[paper["k"] == kmax], unit[unit["k"] == kmax]
    out["capture_moves_escape_k8"] = float(e_paper["escaped"].mean() - e_unit["escaped"].mean())
    keys = ["instance_id", "repeat", "k"]
    both = paper[keys + ["escaped"]].merge(_probe_k(stored, None)[keys + ["escaped"]], on=keys, how="outer",
                                           suffixes=("", "_stored"))
    out["same_escape_as_stored_every_k"] = int(both["escaped"].notna().all() and both["escaped_stored"].notna().all()
                                               and bool((both["escaped"].astype(bool) == both["escaped_stored"].astype(bool)).all()))
    scales = gamma_scales(ratio, sd, int(paper["instances"].iloc[0]), seed)  # one scale per instance, in instance order
    per_truth = capture_failure(e_paper["action"].to_numpy(), e_paper["z_true"].to_numpy(), e_paper["true_c"].to_numpy(float),
                                scales[e_paper["instance_index"].to_numpy().astype(int)])
    out["per_truth_capture.failure_k8"] = float(per_truth.mean())
    out["per_truth_capture.optimism_k8"] = float((per_truth - e_paper["predicted"].to_numpy(float)).mean())
    return out


def run(root: Path, runs: Path, boot: dict[str, Any], workers: int = 1, seed: int = 0,
        draws: int = 0, stored_rows: dict[str, Any] | None = None) -> dict[str, Any]:
    """Keys of ``explain:results.pybullet_escape`` (empty without the engines study's PyBullet run); the per-draw
    escapes go into ``stored_rows[STORED]`` when given."""
    path = root / "engines" / "runs" / "pybullet_B_test_random"
    if not (path / "manifest.json").is_file():
        return {}
    stored = load_run(path)
    kmax = int(stored.config.probes.budget)
    offset, ratio = value("T18-engine-scans.pybullet_offset"), value("T18-engine-scans.pybullet_ratio")
    sd = value("T18-engine-scans.pybullet_ratio_sd")
    paper = _emulated(stored, runs, "pybullet_emulated_paper_scene", offset, ratio, workers)
    unit = _emulated(stored, runs, "pybullet_emulated_paper_boundary_unit_capture", offset, 1.0, workers)
    rows = emulated_rows(paper, unit)
    if stored_rows is not None:
        stored_rows[EMULATED] = rows
    out: dict[str, Any] = {"paper_offset": offset, "paper_ratio": ratio, "paper_ratio_sd": sd}
    out.update(emulated_keys(rows, stored.episodes, kmax, boot, seed))
    escapes = []
    for i in range(draws):
        split = f"pybullet_draw_{i:02d}"
        drawn = _emulated(stored, runs, f"pybullet_emulated_{split}", offset, ratio, workers, split)
        escapes.append(float(_probe_k(drawn.episodes, kmax)["escaped"].mean()))
    table = pd.DataFrame({"draw": np.arange(len(escapes), dtype="int32"), "escape_k8": np.asarray(escapes, float)})
    if stored_rows is not None:
        stored_rows[STORED] = table
    out.update(stored_keys(stored.episodes, table, kmax, boot))
    return out

