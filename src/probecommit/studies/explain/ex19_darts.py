"""Darts' Table II row at the declared prior widths with its truth set redrawn (E138).

Why: the paper reports neither darts' prior nor its six truths. E38 swept the prior's width on our
truths (the blind cells scale with the width, but on our truths Blind-Robust equals Blind-Bayes to a
few per cent where the paper's is 1.35 times it); E78 redrew the truths at our width (the ratio is a
truth-set property, but no truth set reaches cells six times smaller). Cause under test: both
unreported properties at once. At each width of E38's declared grid, E78's redraws (six truths
uniform over that width's prior box, the width's own stored blind actions, each truth's miss from
the model; no engine run) give bands for the two blind cells and their ratio; the paper's
Probe-Robust(5) is read against E38's own interval at that width (docs/decisions.md, "ex19").
Every key is computed by :func:`keys` from the stored rows and E38's published keys, so ``verify``
recomputes them.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex8_blind

FAMILY = "darts"
ARMS = ex8_blind.ARMS
#: The stored rows (each width's blind episodes with truths, targets and actions), beside results.json.
STORED = "ex19_darts_rows.parquet"
#: Redraw seed, truths per set (the paper's six), premise tolerance (relative) and central band (declared).
SEED, N_TRUTHS, PREMISE, CENTRAL = 3801, 6, 0.02, (2.5, 97.5)


def width_runs(root: Path, runs: Path, cfg: dict[str, Any], quick: bool) -> dict[float, Path]:
    """E38's darts runs by width (s = 1: the frozen breadth run), those present under ``root``."""
    from probecommit.studies.breadth import paper_config, quick_config
    from probecommit.studies.explain.breadth import scaled_config

    base = paper_config(FAMILY)
    if quick:
        base = quick_config(base)
    found = {1.0: ex8_blind.run_dir(root, FAMILY, quick)}
    for s in cfg["breadth_prior_scales_quick" if quick else "breadth_prior_scales"]:
        found[float(s)] = Path(runs) / "breadth_prior" / scaled_config(base, float(s)).name
    return {s: p for s, p in sorted(found.items()) if (p / "episodes.parquet").is_file()}


def rows_of(run: Path, scale: float) -> pd.DataFrame:
    """One run's blind episodes (status ok) with each instance's truth and target, tagged with the width."""
    episodes = pd.read_parquet(run / "episodes.parquet")
    episodes = episodes[episodes["method"].isin(ARMS) & (episodes["status"] == "ok")]
    keep = ["instance_id", "repeat", "method", "realized", *[c for c in episodes.columns if c.startswith("action")]]
    instances = pd.read_parquet(run / "instances.parquet")
    cols = ["instance_id", *[c for c in instances.columns if c.startswith(("true_", "ctx_"))]]
    return episodes[keep].merge(instances[cols], on="instance_id", how="left").assign(scale=float(scale))


def model_at(scale: float) -> Any:
    """Darts' model with its prior box scaled about the centre by ``scale`` (E38's ``scaled_config``)."""
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config
    from probecommit.studies.explain.breadth import scaled_config

    return build_model(scaled_config(paper_config(FAMILY), scale))


def width_keys(rows: pd.DataFrame, scale: float, draws: int) -> dict[str, float]:
    """One width's bands: each blind arm's stored cell, the model's on the stored truths (premise) and the central
    band of ``draws`` six-truth redraws; the ratio's band; the paper's cells inside each."""
    from probecommit.studies.paper_values import value

    model = model_at(scale)
    out: dict[str, float] = {}
    cells, premise = {}, True
    for i, arm in enumerate(ARMS):
        part = rows[rows["method"] == arm].drop(columns="scale")
        stored, computed = float(part["realized"].mean()), ex8_blind.model_cell(part, model)
        cells[arm] = ex8_blind.redraw_cells(part, model, N_TRUTHS, draws, SEED + i)
        lo, hi = np.percentile(cells[arm], CENTRAL)
        paper = value(f"tab:breadth.{FAMILY}.{arm}")
        out.update({f"{arm}.stored": stored, f"{arm}.premise_rel_diff": abs(computed - stored) / stored,
                    f"{arm}.mean": float(cells[arm].mean()), f"{arm}.p025": float(lo), f"{arm}.p975": float(hi),
                    f"{arm}.paper_inside": float(lo <= paper <= hi)})
        premise &= abs(computed - stored) <= PREMISE * stored
    ratio = cells["blind_robust"] / cells["blind_bayes"]
    rlo, rhi = np.percentile(ratio, CENTRAL)
    paper_ratio = value(f"tab:breadth.{FAMILY}.blind_robust") / value(f"tab:breadth.{FAMILY}.blind_bayes")
    out.update({"ratio.p025": float(rlo), "ratio.p975": float(rhi), "ratio.paper_inside": float(rlo <= paper_ratio
                                                                                               <= rhi),
                "premise_holds": float(premise)})
    out["blind_inside"] = float(premise and out["blind_bayes.paper_inside"] == out["blind_robust.paper_inside"]
                                == out["ratio.paper_inside"] == 1)
    return out


def implied_width(widths: list[float], values: list[float], target: float) -> float:
    """The width at which ``values`` (increasing with width) reach ``target``, log-log interpolation between the
    grid's neighbouring widths; NaN outside the grid's range."""
    for (s0, v0), (s1, v1) in zip(zip(widths, values), zip(widths[1:], values[1:])):
        if min(v0, v1) <= target <= max(v0, v1) and v0 > 0 and v1 > 0 and v0 != v1:
            return float(math.exp(math.log(s0) + (math.log(target) - math.log(v0))
                                  * (math.log(s1) - math.log(s0)) / (math.log(v1) - math.log(v0))))
    return math.nan


def probed_checks(e38: dict[str, Any], scale: float) -> dict[str, float]:
    """E38's Probe-Robust(5) interval and paired reduction at ``scale`` (its published keys), with the paper's
    Probe-Robust(5) inside and the reduction excluding zero; NaN where E38 has no row at that width."""
    from probecommit.studies.paper_values import value

    def get(name: str) -> float:
        v = e38.get(f"{FAMILY}.s{scale:g}.{name}")
        return math.nan if v is None else float(v)

    lo, hi, plo = get("probe_robust_lo"), get("probe_robust_hi"), get("paired_lo")
    paper = value(f"tab:breadth.{FAMILY}.probe_robust")
    return {"probe_robust_lo": lo, "probe_robust_hi": hi, "probe_robust.paper_inside": float(lo <= paper <= hi),
            "paired_lo": plo, "paired_excludes_zero": float(plo > 0)}


def keys(stored: pd.DataFrame, draws: int, e38: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.ex19_darts`` from the stored rows and E38's published group (``e38``)."""
    from probecommit.studies.paper_values import value

    out: dict[str, Any] = {"draws": float(draws), "n_truths": float(N_TRUTHS)}
    per: dict[float, dict[str, float]] = {}
    for scale, rows in stored.groupby("scale", sort=True):
        s = float(scale)
        per[s] = width_keys(rows, s, draws) | probed_checks(e38, s)
        per[s]["holds"] = float(per[s]["blind_inside"] == per[s]["probe_robust.paper_inside"]
                                == per[s]["paired_excludes_zero"] == 1)
        out.update({f"s{s:g}.{k}": v for k, v in per[s].items()})
    widths = sorted(per)
    holding = [s for s in widths if per[s]["holds"] == 1]
    out.update({"widths": float(len(widths)), "widths_holding": float(len(holding)),
                "first_width": holding[0] if holding else 0.0})
    best = holding[0] if holding else max(widths, key=lambda s: (sum(per[s][k] == 1 for k in (
        "blind_bayes.paper_inside", "blind_robust.paper_inside", "ratio.paper_inside", "probe_robust.paper_inside")),
        -s))
    out["best_width"] = best
    out.update({f"best.{k}": v for k, v in per[best].items()})
    out["ratio.paper"] = value(f"tab:breadth.{FAMILY}.blind_robust") / value(f"tab:breadth.{FAMILY}.blind_bayes")
    for arm in ARMS:  # descriptive: the widths one scene would need for each paper blind cell
        paper = value(f"tab:breadth.{FAMILY}.{arm}")
        out[f"implied.prior.{arm}"] = implied_width(widths, [per[s][f"{arm}.mean"] for s in widths], paper)
        out[f"implied.ours.{arm}"] = implied_width(widths, [per[s][f"{arm}.stored"] for s in widths], paper)
    return out


def run(root: Path, runs: Path, cfg: dict[str, Any], e38: dict[str, Any], quick: bool) -> tuple[dict[str, Any],
                                                                                                  pd.DataFrame]:
    """The keys and the stored rows, for E38's darts widths present under ``root``."""
    found = width_runs(root, runs, cfg, quick)
    if not found:
        return {}, pd.DataFrame()
    stored = pd.concat([rows_of(p, s) for s, p in found.items()], ignore_index=True)
    draws = int(cfg["ex19_darts_draws_quick" if quick else "ex19_darts_draws"])
    return keys(stored, draws, e38), stored


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The keys again from a publication's stored rows and its published E38 group (``verify``)."""
    if not (folder / STORED).is_file() or not published:
        return {}
    e38 = json.loads((folder / "results.json").read_text())["results"].get("breadth_prior", {})
    return keys(pd.read_parquet(folder / STORED), int(published["draws"]), e38)
