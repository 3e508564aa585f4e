"""Grasp's row truth by truth: the paper's decomposition against ours at every squeeze resolution (E73).

Why: Blind-Bayes commits one grip per target, so its success is 0 or 1 per truth, and a truth it
holds can only tie (every probed seed succeeds) or worsen. The paper's own values fix its row's
decomposition (six feasible truths, two held by the blind grip and tied at 80 of 80, one missed by
both arms, three improving from 0.36 to 0.96): its per-truth probed success spans 0 to 1. Ours
(the frozen MuJoCo row; E47/E49's model-exact runs at squeeze resolution c = 1, 2, 4) is read the
same way, to test whether the resolution alone (E49's cause) can give the paper's pattern: the held
truths' ties AND a truth as poorly served as the paper's worst. One new run asks what still worsens
at c = 4: the same study with four times the particles (docs/decisions.md, "ex8").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.runner.config import config_data, parse_config
from probecommit.runner.study import run_study
from probecommit.studies.breadth import FAMILY_K, truth_rows
from probecommit.studies.explain.ex4_grasp import resolution_config

#: The particle rerun's rows (``breadth.truth_rows`` with ``part``), stored beside results.json for verify.
STORED = "ex8_grasp_rows.parquet"
#: The paper's seeds per truth (Table I: 16 x 80) and its two held truths' seeds together.
SEEDS = 80
#: The squeeze resolution and particle factor of the rerun (docs/decisions.md, "ex8").
RESOLUTION, PARTICLE_FACTOR = 4.0, 4
#: The supports thresholds (declared): the two ties not improbable, a truth as low as the paper's lowest gain.
TIE_CHANCE, LOWEST = 0.05, 0.36


def paper_keys() -> dict[str, float]:
    """The paper's row decomposed (its printed Table II cells and Sec. V-A's words)."""
    from probecommit.studies.paper_values import value

    n, bb, pr = 6, value("tab:breadth.grasp.blind_bayes"), value("tab:breadth.grasp.probe_robust")
    held = float(round(bb * n))
    lo, hi = value("T09-grasp.improve_min"), value("T09-grasp.improve_max")
    middle = n * pr - held - lo - hi  # the third improving truth (the held ones at 1, the other tie at 0)
    return {"paper.n_feasible": float(n), "paper.n_held": held, "paper.improve_middle": float(middle),
            "paper.consistent": float(lo - 0.003 <= middle <= hi + 0.003)}


def per_truth(rows: pd.DataFrame, k: int = FAMILY_K["grasp"]) -> pd.DataFrame:
    """Per feasible truth: Blind-Bayes success, Probe-Robust(k) success, its failures and episodes."""
    ok = rows[(rows["status"] == "ok") & rows["feasible"].astype(bool)]
    blind = 1.0 - ok[ok["method"] == "blind_bayes"].groupby("truth")["realized"].mean()
    probe = ok[(ok["method"] == "probe_robust") & (ok["k"] == k)].groupby("truth")["realized"]
    return pd.DataFrame({"blind": blind, "probe": 1.0 - probe.mean(), "fail": probe.sum().astype(float),
                         "n": probe.size().astype(float)}).dropna()


def part_keys(rows: pd.DataFrame) -> dict[str, float]:
    """One run's keys: the held truths, their failures and the chance of the paper's two ties at that rate,
    the lowest probed success, the worsening truths (and how many the blind grip does not hold)."""
    t = per_truth(rows)
    held = t[t["blind"] >= 0.5]
    rate = float(held["fail"].sum() / held["n"].sum()) if len(held) else float("nan")
    rest = t[t["blind"] < 0.5]
    diff = t["probe"] - t["blind"]
    return {"n_feasible": float(len(t)), "n_held": float(len(held)), "held_failures": float(held["fail"].sum()),
            "held_episodes": float(held["n"].sum()), "held_failure_rate": rate,
            "paper_ties_chance": float((1.0 - rate) ** (2 * SEEDS)) if len(held) else float("nan"),
            "other_failure_rate": float(rest["fail"].sum() / rest["n"].sum()) if len(rest) else float("nan"),
            "failure_rate": float(t["fail"].sum() / t["n"].sum()) if len(t) else float("nan"),
            "lowest_probe_success": float(t["probe"].min()), "highest_probe_success": float(t["probe"].max()),
            "n_worse": float((diff < 0).sum()), "n_worse_not_held": float(((diff < 0) & (t["blind"] < 0.5)).sum())}


#: The runs read, by part name: the frozen MuJoCo row, E47's model-exact run (c = 1), E49's (c = 2, 4).
PARTS = ("mujoco", "c1", "c2", "c4")


def keys(mujoco: pd.DataFrame, ex4_rows: pd.DataFrame, own: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex8_grasp`` from the stored rows (one function for the step and verify):
    ``mujoco`` Table II's sign-count rows (grasp), ``ex4_rows`` E49's stored rows, ``own`` the particle rerun."""
    parts = {"mujoco": mujoco[mujoco["family"] == "grasp"] if "family" in mujoco else mujoco}
    for name, part in (("c1", "frozen"), ("c2", "c2"), ("c4", "c4")):
        sel = ex4_rows[ex4_rows["part"] == part]
        if len(sel):
            parts[name] = sel
    out: dict[str, Any] = paper_keys()
    for name, rows in parts.items():
        out.update({f"{name}.{k}": v for k, v in part_keys(rows).items()})
    if len(own):
        out.update({f"c4_particles.{k}": v for k, v in part_keys(own).items()})
        out["c4_particles.factor"] = float(PARTICLE_FACTOR)
    both = [name for name in parts if out[f"{name}.paper_ties_chance"] >= TIE_CHANCE
            and out[f"{name}.lowest_probe_success"] <= LOWEST]
    out["runs_with_both"] = float(len(both))
    out["runs_with_ties"] = float(sum(out[f"{n}.paper_ties_chance"] >= TIE_CHANCE for n in parts))
    out["runs_with_low_truth"] = float(sum(out[f"{n}.lowest_probe_success"] <= LOWEST for n in parts))
    out["runs"] = float(len(parts))
    out["tie_chance_threshold"] = float(TIE_CHANCE)
    return out


def particle_config(quick: bool) -> Any:
    """E49's c = 4 config with four times its particles (nothing else changed)."""
    data = config_data(resolution_config(RESOLUTION, quick))
    data["belief"] = {**data["belief"], "particles": int(data["belief"]["particles"]) * PARTICLE_FACTOR}
    data["name"] = f"grasp_analytic_resolution{RESOLUTION:g}_particles{PARTICLE_FACTOR}x"
    return parse_config(data)


def _run_particles(quick: bool, path: Path, workers: int) -> None:
    """The particle rerun's study (``run``; the config is built here, as it does not pickle)."""
    run_study(particle_config(quick), path, workers=workers, threads=1)


def run(root: Path, runs: Path, ex4_rows: pd.DataFrame | None, quick: bool,
        workers: int = 1) -> tuple[dict[str, Any], pd.DataFrame]:
    """The particle rerun, then the keys from it, Table II's stored grasp rows and E49's rows."""
    from probecommit.runner.aside import in_own_process

    config = particle_config(quick)
    path = runs / config.name
    # in a process of its own: four times the particles took the explain process from 447 to 613 MB (issue 42)
    in_own_process(_run_particles, quick, path, workers)
    own = truth_rows(config, path).assign(part="c4_particles")
    table = Path(root) / "breadth" / "results" / "sign_flip_rows.parquet"
    if not table.is_file() or ex4_rows is None or not len(ex4_rows):
        return {}, own
    return keys(pd.read_parquet(table), ex4_rows, own), own


def recompute(folder: Path) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``); empty when one is missing."""
    from probecommit.studies.explain import ex4_grasp

    paths = (folder.parent / "breadth" / "sign_flip_rows.parquet", folder / ex4_grasp.STORED, folder / STORED)
    if not all(p.is_file() for p in paths):
        return {}
    return keys(*(pd.read_parquet(p) for p in paths))


__all__ = ["STORED", "keys", "paper_keys", "part_keys", "per_truth", "recompute", "run"]
