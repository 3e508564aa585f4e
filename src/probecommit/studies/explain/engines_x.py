"""PyBullet's capture window against the spread the paper reports for it (E30).

Why: the paper's PyBullet capture window is 1.21 x the analytic one "with SD 0.69 of that
ratio across the 24 development truths"; ours is 1.000 with an SD near 1e-4. A mean over 24
truths with that SD has a standard error of 0.69 / sqrt(24): the interval below is the
paper's own sampling interval of its mean (normal approximation), computed from its printed
mean and SD and the number of truths both scans use. It says whether the paper's mean is
distinguishable from ours given its own spread; it does not say why the paper's per-truth
ratios spread so much more than ours.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.paper_values import value

Z95 = 1.959963984540054


def mean_interval(mean: float, sd: float, n: int) -> list[float]:
    """``[mean, lo, hi]``: the 95 % normal-approximation interval of a mean of ``n`` values with SD ``sd``."""
    half = Z95 * sd / math.sqrt(n)
    return [mean, mean - half, mean + half]


def keys(scans: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.engines_x`` from the engines study's scan summaries (``results.scans``, or
    ``studies.engines.scan_summaries`` of its stored ``engine_scans.parquet`` in verify)."""
    capture = scans["pybullet"]["capture"]
    n = int(capture["truths"])
    iv = mean_interval(value("T18-engine-scans.pybullet_ratio"), value("T18-engine-scans.pybullet_ratio_sd"), n)
    ours = float(capture["ratio_mean"])
    return {"pybullet_capture.ours": ours, "pybullet_capture.ours_sd": float(capture["ratio_sd"]),
            "pybullet_capture.truths": n, "pybullet_capture.paper_mean_interval": iv,
            "pybullet_capture.ours_inside_paper_interval": int(iv[1] <= ours <= iv[2])}


def physx_ours(scans: dict[str, Any]) -> dict[str, float]:
    """``physx_capture.ours.*``: our PhysX capture window and boundary offset, from the same scan summaries."""
    if "sapien" not in scans:
        return {}
    return {"ours.capture_ratio": float(scans["sapien"]["capture"]["ratio_mean"]),
            "ours.capture_ratio_sd": float(scans["sapien"]["capture"]["ratio_sd"]),
            "ours.boundary_offset": float(scans["sapien"]["boundary"]["delta"])}


def run(root: Path) -> dict[str, Any]:
    """Keys of ``explain:results.engines_x`` (empty when the engines study is not under ``root``)."""
    path = root / "engines" / "results" / "results.json"
    if not path.is_file():
        return {}
    return keys(json.loads(path.read_text())["results"]["scans"])


#: The emulated PhysX scene's final-budget Probe-Robust rows per tap model (``physx_capture.emulated.*`` read them).
EMULATED = "physx_emulated_episodes.parquet"
EMULATED_COLUMNS = ("variant", "instance_id", "repeat", "k", "action", "z_true", "true_c", "predicted", "realized",
                    "escaped", "covered")


def emulated_table(parts: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """The stored rows: each tap model's final-budget rows (with ``variant`` and the instance's ``true_c``)."""
    return pd.concat([part[list(EMULATED_COLUMNS)] for part in parts], ignore_index=True)


def emulated_keys(rows: pd.DataFrame, capture_scale: float, boot: Mapping[str, int]) -> dict[str, Any]:
    """``physx_capture.emulated.*``: each tap model's failure and optimism with the aims re-scored under the paper's
    PhysX capture window and the model's, its escape and coverage, whether the stored failure is the re-scored one,
    and the paired failure differences against the deployed model (cluster bootstrap)."""
    from probecommit.audit.stats import paired_bootstrap
    from probecommit.studies.explain.stats import capture_failure

    out: dict[str, Any] = {}
    tables = {}
    for variant, part in rows.groupby("variant", sort=False):
        part = part.drop(columns="variant").reset_index(drop=True)
        for scale_name, scale in (("paper_capture", capture_scale), ("model_capture", 1.0)):
            realized = capture_failure(part["action"].to_numpy(), part["z_true"].to_numpy(), part["true_c"].to_numpy(), scale)
            pre = f"emulated.{scale_name}.{variant}"
            out[f"{pre}.failure"] = float(realized.mean())
            out[f"{pre}.optimism"] = float((realized - part["predicted"].to_numpy(float)).mean())
            tables[(scale_name, variant)] = part.assign(realized=realized)
        out[f"emulated.{variant}.escape"] = float(part["escaped"].mean())
        out[f"emulated.{variant}.episode_coverage"] = float(part["covered"].mean())
        out[f"emulated.{variant}.cluster_coverage"] = float(part.groupby("instance_id")["covered"].all().mean())
        mine = tables[("paper_capture", variant)]["realized"].to_numpy(float)
        out[f"emulated.{variant}.stored_equals_recomputed"] = int(np.array_equal(part["realized"].to_numpy(float), mine))
    b = dict(resamples=int(boot["resamples"]), seed=int(boot["seed"]))
    for scale_name in ("paper_capture", "model_capture"):
        for variant in ("mj_offset", "own_scan"):
            d = paired_bootstrap(tables[(scale_name, "deployed")], tables[(scale_name, variant)], "realized", **b)
            out[f"emulated.{scale_name}.{variant}.paired_failure"] = [float(d.difference.estimate), float(d.difference.lo),
                                                                       float(d.difference.hi)]
    return out
