"""A test-only faulty engine: NaN on one instance's tap, an exception on one aim.

Injected by monkeypatching ``probecommit.runner.build.build_simulator``, which the
runner looks up at call time; that reaches serial runs (and the CLI in-process).
"""

from __future__ import annotations

import numpy as np

import probecommit.runner.build as build
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator


class FaultyAnalyticSimulator(AnalyticInsertionSimulator):
    """The analytic engine, except: ``tap_reading`` is NaN at ``(nan_x, nan_u)`` (every
    tap of ``nan_x`` if ``nan_u`` is None) and ``peg_depth`` raises at ``(raise_x, raise_aim)``."""

    def __init__(self, nan_x: float, nan_u: float, raise_x: float, raise_aim: float, **kwargs) -> None:
        super().__init__(**kwargs)
        self.nan_x, self.nan_u, self.raise_x, self.raise_aim = nan_x, nan_u, raise_x, raise_aim

    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        if x_hole == self.nan_x and (self.nan_u is None or u == self.nan_u):
            return float("nan")
        return super().tap_reading(x_hole, c, u)

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        if x_hole == self.raise_x and a == self.raise_aim:
            raise RuntimeError("contact solver diverged")
        return super().peg_depth(x_hole, c, a)


def inject(monkeypatch, **faults) -> None:
    """Make every analytic simulator the runner builds a faulty one."""
    real = build.build_simulator

    def faulty(cfg):
        sim = real(cfg)
        if cfg.simulator.engine != "analytic":
            return sim
        return FaultyAnalyticSimulator(
            boundary_offset=sim.boundary_offset, capture_scale=sim.capture_scale,
            noise_sigma=sim.noise_sigma, aim_offset=sim.aim_offset, **faults,
        )

    monkeypatch.setattr(build, "build_simulator", faulty)


def pick_faults(clean_dir) -> dict:
    """From a clean run: a tap some (not all) repeats of one instance make, and an aim
    another instance commits to in some (not all) of its episodes."""
    import pandas as pd

    instances = pd.read_parquet(clean_dir / "instances.parquet").set_index("instance_id")
    probes = pd.read_parquet(clean_dir / "probes.parquet")
    episodes = pd.read_parquet(clean_dir / "episodes.parquet")
    nan_id = instances.index[1]
    mine = probes[probes.instance_id == nan_id]
    n_rep = mine["repeat"].nunique()
    hits = mine.groupby("u")["repeat"].nunique()
    nan_u = float(hits[(hits > 0) & (hits < n_rep)].index[0])
    raise_id = instances.index[3]
    theirs = episodes[(episodes.instance_id == raise_id) & (episodes.method == "probe_robust")]
    raise_aim = float(theirs["action"].value_counts().index[0])
    assert (theirs["action"] != raise_aim).any()
    return {
        "nan_id": nan_id, "nan_u": nan_u, "raise_id": raise_id, "raise_aim": raise_aim,
        "faults": {
            "nan_x": float(instances.loc[nan_id, "true_x_hole"]), "nan_u": nan_u,
            "raise_x": float(instances.loc[raise_id, "true_x_hole"]), "raise_aim": raise_aim,
        },
        "nan_repeats": sorted(mine.loc[mine.u == nan_u, "repeat"].unique().tolist()),
    }


__all__ = ["FaultyAnalyticSimulator", "inject", "pick_faults", "np"]
