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
#: The stored rows (each width's blind episodes with truths, targets and actions), beside results.json: darts'
#: (E138) and the other rows' under the same rule (E140 hinge, E141 push1d; group ``ex19_widths``).
STORED = "ex19_darts_rows.parquet"
STORED_WIDTHS = "ex19_widths_rows.parquet"
#: The rows and their truth-set sizes (the paper's: six for darts and the hinge, "6 x 3"; push1d's 81 instances are
#: 27 truths x 3 targets, as E75's), and the rows E140, E141 run in that order.
N_TRUTHS = {"darts": 6, "hinge": 6, "push1d": 27}
OTHERS = ("hinge", "push1d")
#: Redraw seed, premise tolerance (relative) and central band (declared).
SEED, PREMISE, CENTRAL = 3801, 0.02, (2.5, 97.5)


def printed(family: str) -> tuple[str, ...]:
    """The blind cells of the row the paper prints."""
    from probecommit.studies.paper_values import PRINTED

    return tuple(arm for arm in ARMS if f"tab:breadth.{family}.{arm}" in PRINTED)


def width_runs(root: Path, runs: Path, cfg: dict[str, Any], quick: bool, family: str = FAMILY) -> dict[float, Path]:
    """The prior sweep's runs of ``family`` by width (s = 1: the frozen breadth run), those present under ``root``."""
    from probecommit.studies.breadth import paper_config, quick_config
    from probecommit.studies.explain.breadth import scaled_config

    base = paper_config(family)
    if quick:
        base = quick_config(base)
    found = {1.0: ex8_blind.run_dir(root, family, quick)}
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


def model_at(scale: float, family: str = FAMILY) -> Any:
    """The row's model with its prior box scaled about the centre by ``scale`` (E38's ``scaled_config``)."""
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config
    from probecommit.studies.explain.breadth import scaled_config

    return build_model(scaled_config(paper_config(family), scale))


def width_keys(rows: pd.DataFrame, scale: float, draws: int, family: str = FAMILY) -> dict[str, float]:
    """One width's bands: each blind arm's stored cell, the model's on the stored truths (premise) and the central
    band of ``draws`` redraws of a truth set of the paper's size; the ratio's band where both cells are printed; the
    paper's printed cells inside each."""
    from probecommit.studies.paper_values import value

    model, shown = model_at(scale, family), printed(family)
    out: dict[str, float] = {}
    cells, premise = {}, True
    for i, arm in enumerate(ARMS):
        part = rows[rows["method"] == arm].drop(columns="scale")
        stored, computed = float(part["realized"].mean()), ex8_blind.model_cell(part, model)
        cells[arm] = ex8_blind.redraw_cells(part, model, N_TRUTHS[family], draws, SEED + i)
        lo, hi = np.percentile(cells[arm], CENTRAL)
        out.update({f"{arm}.stored": stored, f"{arm}.premise_rel_diff": abs(computed - stored) / stored,
                    f"{arm}.mean": float(cells[arm].mean()), f"{arm}.p025": float(lo), f"{arm}.p975": float(hi)})
        if arm in shown:
            out[f"{arm}.paper_inside"] = float(lo <= value(f"tab:breadth.{family}.{arm}") <= hi)
        premise &= abs(computed - stored) <= PREMISE * stored
    flags = [f"{arm}.paper_inside" for arm in shown]
    if len(shown) == 2:
        ratio = cells["blind_robust"] / cells["blind_bayes"]
        rlo, rhi = np.percentile(ratio, CENTRAL)
        paper_ratio = value(f"tab:breadth.{family}.blind_robust") / value(f"tab:breadth.{family}.blind_bayes")
        out.update({"ratio.p025": float(rlo), "ratio.p975": float(rhi),
                    "ratio.paper_inside": float(rlo <= paper_ratio <= rhi)})
        flags.append("ratio.paper_inside")
    out["premise_holds"] = float(premise)
    out["blind_inside"] = float(premise and all(out[f] == 1 for f in flags))
    return out


def implied_width(widths: list[float], values: list[float], target: float) -> float:
    """The width at which ``values`` (increasing with width) reach ``target``, log-log interpolation between the
    grid's neighbouring widths; NaN outside the grid's range."""
    for (s0, v0), (s1, v1) in zip(zip(widths, values), zip(widths[1:], values[1:])):
        if min(v0, v1) <= target <= max(v0, v1) and v0 > 0 and v1 > 0 and v0 != v1:
            return float(math.exp(math.log(s0) + (math.log(target) - math.log(v0))
                                  * (math.log(s1) - math.log(s0)) / (math.log(v1) - math.log(v0))))
    return math.nan


def probed_checks(e38: dict[str, Any], scale: float, family: str = FAMILY) -> dict[str, float]:
    """E38's Probe-Robust(5) interval and paired reduction at ``scale`` (its published keys), with the paper's
    Probe-Robust(5) inside and the reduction excluding zero; NaN where E38 has no row at that width."""
    from probecommit.studies.paper_values import value

    def get(name: str) -> float:
        v = e38.get(f"{family}.s{scale:g}.{name}")
        return math.nan if v is None else float(v)

    lo, hi, plo = get("probe_robust_lo"), get("probe_robust_hi"), get("paired_lo")
    paper = value(f"tab:breadth.{family}.probe_robust")
    return {"probe_robust_lo": lo, "probe_robust_hi": hi, "probe_robust.paper_inside": float(lo <= paper <= hi),
            "paired_lo": plo, "paired_excludes_zero": float(plo > 0)}


def keys(stored: pd.DataFrame, draws: int, e38: dict[str, Any], family: str = FAMILY) -> dict[str, Any]:
    """Keys of ``explain:results.ex19_darts`` (one row's) from the stored rows and the prior sweep's published group
    (``e38``: ``breadth_prior``)."""
    from probecommit.studies.paper_values import value

    out: dict[str, Any] = {"draws": float(draws), "n_truths": float(N_TRUTHS[family])}
    per: dict[float, dict[str, float]] = {}
    shown = printed(family)
    for scale, rows in stored.groupby("scale", sort=True):
        s = float(scale)
        per[s] = width_keys(rows, s, draws, family) | probed_checks(e38, s, family)
        per[s]["holds"] = float(per[s]["blind_inside"] == per[s]["probe_robust.paper_inside"]
                                == per[s]["paired_excludes_zero"] == 1)
        out.update({f"s{s:g}.{k}": v for k, v in per[s].items()})
    widths = sorted(per)
    holding = [s for s in widths if per[s]["holds"] == 1]
    out.update({"widths": float(len(widths)), "widths_holding": float(len(holding)),
                "first_width": holding[0] if holding else 0.0})
    best = holding[0] if holding else max(widths, key=lambda s: (sum(per[s].get(k) == 1 for k in (
        "blind_bayes.paper_inside", "blind_robust.paper_inside", "ratio.paper_inside", "probe_robust.paper_inside")),
        -s))
    out["best_width"] = best
    out.update({f"best.{k}": v for k, v in per[best].items()})
    if len(shown) == 2:
        out["ratio.paper"] = value(f"tab:breadth.{family}.blind_robust") / value(f"tab:breadth.{family}.blind_bayes")
    for arm in shown:  # descriptive: the widths one scene would need for each paper blind cell
        paper = value(f"tab:breadth.{family}.{arm}")
        out[f"implied.prior.{arm}"] = implied_width(widths, [per[s][f"{arm}.mean"] for s in widths], paper)
        out[f"implied.ours.{arm}"] = implied_width(widths, [per[s][f"{arm}.stored"] for s in widths], paper)
    return out


def run(root: Path, runs: Path, cfg: dict[str, Any], e38: dict[str, Any], quick: bool,
        family: str = FAMILY) -> tuple[dict[str, Any], pd.DataFrame]:
    """One row's keys and stored rows, for the prior sweep's widths of ``family`` present under ``root``."""
    found = width_runs(root, runs, cfg, quick, family)
    if not found:
        return {}, pd.DataFrame()
    stored = pd.concat([rows_of(p, s) for s, p in found.items()], ignore_index=True)
    draws = int(cfg["ex19_darts_draws_quick" if quick else "ex19_darts_draws"])
    return keys(stored, draws, e38, family), stored


def widths_keys(stored: pd.DataFrame, draws: int, e38: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.ex19_widths`` (``<family>.*``, E138's keys per row) from the rows of ``OTHERS``."""
    return {f"{family}.{k}": v for family, part in stored.groupby("family", sort=False)
            for k, v in keys(part.drop(columns="family"), draws, e38, str(family)).items()}


def run_widths(root: Path, runs: Path, cfg: dict[str, Any], e38: dict[str, Any],
               quick: bool) -> tuple[dict[str, Any], pd.DataFrame]:
    """E140/E141: the hinge's and push1d's rows under E138's rule (the rows present under ``root``)."""
    parts = [run(root, runs, cfg, e38, quick, family)[1].assign(family=family) for family in OTHERS]
    parts = [p for p in parts if len(p)]
    if not parts:
        return {}, pd.DataFrame()
    stored = pd.concat(parts, ignore_index=True)
    draws = int(cfg["ex19_darts_draws_quick" if quick else "ex19_darts_draws"])
    return widths_keys(stored, draws, e38), stored


def _published_sweep(folder: Path) -> dict[str, Any]:
    """The prior sweep's published group (``breadth_prior``; verify recomputes it from its own rows)."""
    path = folder / "results.json"
    return json.loads(path.read_text())["results"].get("breadth_prior", {}) if path.is_file() else {}


def recompute(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """E138's keys again from a publication's stored rows and its published prior sweep (``verify``)."""
    if not (folder / STORED).is_file() or not published:
        return {}
    return keys(pd.read_parquet(folder / STORED), int(published["draws"]), _published_sweep(folder))


def recompute_widths(folder: Path, published: dict[str, Any]) -> dict[str, Any]:
    """E140/E141's keys again (``verify``), with the published draw count."""
    if not (folder / STORED_WIDTHS).is_file() or not published:
        return {}
    draws = int(next(v for k, v in published.items() if k.endswith(".draws")))
    return widths_keys(pd.read_parquet(folder / STORED_WIDTHS), draws, _published_sweep(folder))
