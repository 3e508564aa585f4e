"""The hinge's probe magnitudes swept (E158).

Why: Table I gives the hinge's probe as "coast" with sigma = 0.02 rad, never its release speeds; ours were chosen from
physical sense. E124 tested one alternative grid, and E157 showed that our belief follows the exact posterior of the
readings, so what is left of the hinge's probed-cell difference is the information five coasts carry, which their
unreported magnitudes set. Declared sweep (docs/decisions.md, "ex22", E158): the frozen speeds times c in {1, 1.25,
1.5, 1.75, 2}, everything else frozen, Probe-Robust at k = 2 and 5 on the closed-form scene; the rule asks for both of
the paper's curve points and its k2 / k5 ratio at one scale. Every key is computed by :func:`keys` from the stored
rows, so ``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain.stored import recompute_stored

#: The family, its declared scales (c = 1: the premise, the frozen grid on the closed-form scene) and the premise's
#: tolerance (relative, the closed form against the stored MuJoCo cell; E94/E124's).
FAMILY, SCALES, PREMISE = "hinge", (1.0, 1.25, 1.5, 1.75, 2.0), 0.05
#: The stored rows (every row the keys read), beside results.json.
STORED = "ex22_magnitude_rows.parquet"
#: The budgets of the paper's curve the rule reads.
BUDGETS = (2, 5)
#: Cluster bootstrap as Table II's cells (``studies.breadth.run_breadth``'s defaults), the ratio's too.
RESAMPLES, SEED = 2000, 0


def label(scale: float) -> str:
    """A scale's key part: ``c125`` for 1.25 (no dot inside a key's name)."""
    return f"c{round(scale * 100):03d}"


def part_cells(sel: pd.DataFrame, part: str) -> dict[str, float]:
    """One probe set's Probe-Robust(k) cells with their 95 % intervals and its k2/k5 ratio with its interval, keyed
    under ``part`` (E158 here, E174-E177 in ``ex25_uniform``)."""
    from probecommit.studies.explain.ex22_exact import _cell

    out: dict[str, float] = {}
    for k in BUDGETS:
        m, lo, hi = _cell(sel[sel["k"] == k])
        out.update({f"{part}.k{k}": m, f"{part}.k{k}_lo": lo, f"{part}.k{k}_hi": hi})
    r, rlo, rhi = ratio_interval(sel)
    out.update({f"{part}.ratio_k2_k5": r, f"{part}.ratio_lo": rlo, f"{part}.ratio_hi": rhi})
    return out


def ratio_interval(rows: pd.DataFrame, resamples: int = RESAMPLES, seed: int = SEED) -> tuple[float, float, float]:
    """Probe-Robust(2) / Probe-Robust(5) and its 95 % cluster-bootstrap interval: instances resampled with
    replacement, each drawn instance's episodes at both budgets kept together (percentiles 2.5, 97.5)."""
    ids = pd.Index(pd.unique(rows["instance_id"]))
    sums, counts = np.zeros((2, len(ids))), np.zeros((2, len(ids)))
    for b, k in enumerate(BUDGETS):
        part = rows[rows["k"] == k]
        at = ids.get_indexer(part["instance_id"])
        np.add.at(sums[b], at, part["realized"].to_numpy(float))
        np.add.at(counts[b], at, 1.0)
    point = (sums[0].sum() / counts[0].sum()) / (sums[1].sum() / counts[1].sum())
    draw = np.random.default_rng(seed).integers(0, len(ids), (resamples, len(ids)))
    pick = lambda a: a[:, draw].sum(axis=2)  # noqa: E731  [2, resamples]
    s, n = pick(sums), pick(counts)
    ratios = (s[0] / n[0]) / (s[1] / n[1])
    lo, hi = np.percentile(ratios, (2.5, 97.5))
    return float(point), float(lo), float(hi)


def keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Keys of ``explain:results.ex22_magnitude`` from the stored rows (one function for the step and verify)."""
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    p5, p2 = value(f"tab:breadth.{FAMILY}.probe_robust"), implied_k2(FAMILY)
    out: dict[str, Any] = {"paper.k5": p5, "paper.k2_implied": p2, "paper.ratio_k2_k5": p2 / p5,
                           "resamples": float(RESAMPLES)}
    for part in ("stored", *(label(c) for c in SCALES)):
        out.update(part_cells(rows[rows["part"] == part], part))
    diff = abs(out[f"{label(1.0)}.k5"] - out["stored.k5"]) / out["stored.k5"]
    out.update({"premise_rel_diff": diff, "premise_tolerance": PREMISE, "premise_holds": float(diff <= PREMISE)})
    holding = []
    for c in SCALES[1:]:
        s = label(c)
        flags = {"k5_paper_inside": out[f"{s}.k5_lo"] <= p5 <= out[f"{s}.k5_hi"],
                 "k2_paper_inside": out[f"{s}.k2_lo"] <= p2 <= out[f"{s}.k2_hi"],
                 "ratio_paper_inside": out[f"{s}.ratio_lo"] <= p2 / p5 <= out[f"{s}.ratio_hi"]}
        out.update({f"{s}.{name}": float(ok) for name, ok in flags.items()})
        out[f"{s}.holds"] = float(diff <= PREMISE and all(flags.values()))
        if out[f"{s}.holds"]:
            holding.append(c)
    out.update({"scales_swept": float(len(SCALES) - 1), "scales_holding": float(len(holding)),
                "first_scale": float(holding[0]) if holding else 0.0, "holds": float(bool(holding))})
    return out


def _probe_rows(episodes: pd.DataFrame, part: str) -> pd.DataFrame:
    ep = episodes[(episodes["method"] == "probe_robust") & episodes["k"].isin(BUDGETS) & (episodes["status"] == "ok")]
    return pd.DataFrame({"part": part, "instance_id": ep["instance_id"].to_numpy(), "repeat": ep["repeat"].to_numpy(np.int64),
                         "k": ep["k"].to_numpy(np.int64), "realized": ep["realized"].to_numpy(float)})


def run(root: Path, quick: bool = False) -> tuple[dict[str, Any], pd.DataFrame]:
    """The keys and the stored rows: the frozen run's Probe-Robust episodes and one closed-form run per scale."""
    from probecommit.runner.build import build_model
    from probecommit.studies.explain.ex8_blind import run_dir
    from probecommit.studies.explain.ex16_reach import _config, episodes_with_grid

    run = run_dir(root, FAMILY, quick)
    if not (run / "episodes.parquet").is_file():
        return {}, pd.DataFrame()
    config = _config(FAMILY, "analytic", quick)
    frozen = np.asarray(build_model(config).probe_grid, float)[:, 0]
    frames = [_probe_rows(pd.read_parquet(run / "episodes.parquet"), "stored")]
    for c in SCALES:
        grid = tuple(float(round(u * c, 10)) for u in frozen)
        frames.append(_probe_rows(episodes_with_grid(config, None if c == 1.0 else grid), label(c)))
    rows = pd.concat(frames, ignore_index=True)
    return keys(rows), rows


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows (``verify``)."""
    return recompute_stored(folder, published, STORED, keys)
