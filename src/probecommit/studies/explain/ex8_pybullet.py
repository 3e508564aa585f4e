"""2-D push on PyBullet: does our scene need the paper's residual model (E74)?

Why: Table II's caption says the paper's PyBullet row runs the MuJoCo-fitted analytic model
(Probe-Robust 0.141) and that a residual model, fitted to PyBullet itself, reaches 0.115: the
paper's MuJoCo-fitted model misfits its PyBullet scene, and the misfit costs probed miss. Ours
runs the MuJoCo-fitted model too. If our PyBullet scene reads like our MuJoCo scene and our model
fits it to within the probe noise, our row is the paper's residual-model condition, and the
paper's number under that condition is the one to compare. Measured on the frozen runs' own
probes (same instances, seeds and pulses on both engines): the engines' reading difference, and
the model's bias per truth and pulse (docs/decisions.md, "ex8").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

#: The paired readings the keys are computed from, stored beside results.json for verify.
STORED = "ex8_pybullet_readings.parquet"
#: Premise thresholds (declared): the engines agree to a tenth of sigma; no cell's mean residual beyond 3 SE.
ENGINE_FRACTION, BIAS_SE = 0.1, 3.0


FAMILIES = ("push2d", "push2d_pybullet")


def readings(root: Path, quick: bool = False) -> pd.DataFrame:
    """The frozen push2d (MuJoCo) and push2d_pybullet probes paired by instance, repeat and probe index, with the
    truth (latents) of each instance."""
    from probecommit.studies.explain.ex8_blind import run_dir

    mj, pb = (pd.read_parquet(run_dir(root, name, quick) / "probes.parquet") for name in FAMILIES)
    truths = pd.read_parquet(run_dir(root, "push2d_pybullet", quick) / "instances.parquet")
    truths = truths[["instance_id", *[c for c in truths.columns if c.startswith("true_")]]]
    ycols = [c for c in mj.columns if c.startswith("y_")]
    pair = mj.merge(pb, on=["instance_id", "repeat", "j"], suffixes=("_mujoco", "_pybullet"), validate="one_to_one")
    out = pair[["instance_id", "repeat", "j", "u_mujoco", "u_pybullet",
                *[f"{c}_{e}" for c in ycols for e in ("mujoco", "pybullet")]]]
    return out.merge(truths, on="instance_id", how="left")


def keys(rows: pd.DataFrame) -> dict[str, float]:
    """Keys of ``explain:results.ex8_pybullet`` from the paired readings (one function for the step and verify)."""
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config

    model = build_model(paper_config("push2d_pybullet"))
    matched = float((rows["u_mujoco"] == rows["u_pybullet"]).all())  # same pulses: the runs are paired
    rows = rows.rename(columns={"u_pybullet": "u"})
    theta = rows[[f"true_{n}" for n in model.latent_names]].to_numpy(float)
    pred = model.predict(rows[["u"]].to_numpy(float), theta[:, None, :])[:, 0, :]
    dims = sorted(c[: -len("_pybullet")] for c in rows.columns if c.startswith("y_") and c.endswith("_pybullet"))
    pb = rows[[f"{c}_pybullet" for c in dims]].to_numpy(float)
    mj = rows[[f"{c}_mujoco" for c in dims]].to_numpy(float)
    resid = pd.DataFrame(pb - pred, columns=dims).assign(
        truth=rows[[f"true_{n}" for n in model.latent_names]].astype(str).agg(",".join, axis=1), u=rows["u"])
    cells = resid.groupby(["truth", "u"])[dims].agg(["mean", "count"])
    means = np.abs(np.stack([cells[(d, "mean")].to_numpy() for d in dims]))
    counts = np.stack([cells[(d, "count")].to_numpy() for d in dims])
    sigma = float(model.sigma)
    bias_se = float(np.max(means * np.sqrt(counts) / sigma))
    engine = float(np.max(np.abs(pb - mj)))
    return {"readings": float(len(rows)), "sigma_m": sigma, "engine_max_difference_m": engine,
            "engine_mean_difference_m": float(np.mean(np.abs(pb - mj))),
            "model_residual_sd_m": float(np.std(pb - pred)), "model_max_cell_bias_m": float(np.max(means)),
            "model_max_cell_bias_se": bias_se, "cells": float(means.size), "pulses_match": matched,
            "premise_holds": float(matched == 1 and engine <= ENGINE_FRACTION * sigma and bias_se <= BIAS_SE)}


def run(root: Path, quick: bool = False) -> tuple[dict[str, float], pd.DataFrame]:
    """The keys and the stored rows; none when the breadth study's two runs are not under ``root``."""
    from probecommit.studies.explain.ex8_blind import run_dir

    if not all((run_dir(root, name, quick) / "probes.parquet").is_file() for name in FAMILIES):
        return {}, pd.DataFrame()
    rows = readings(root, quick)
    return keys(rows), rows


def recompute(folder: Path) -> dict[str, float]:
    """The keys again from a publication's stored readings (``verify``); empty when they are not there."""
    return keys(pd.read_parquet(folder / STORED)) if (folder / STORED).is_file() else {}
