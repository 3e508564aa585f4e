"""Table II's families under the one scene property the paper does not report: the prior's width (E35..E44).

Why: the paper gives each family's latents, probe noise, budgets and instance counts, never
the prior over the latents (docs/families.md: every prior is our choice). The blind cells are
set by the prior's width against the targets, and the probed cells by the width against the
probe noise, so a different prior moves every cell. Each family is rerun with its prior scaled
about its centre by ``s`` (truths kept at the same relative positions, everything else frozen)
over the grid declared in ``configs/paper/explain.yaml`` (docs/decisions.md says why), and we
ask: do the paper's cells lie inside the span of our intervals over the sweep, and do the
paper's qualitative claims (probing reduces the miss; the paired reduction excludes zero) hold
at every width? The frozen study's own row (s = 1, the paper's instance counts) is part of the
span; the sweep runs use fewer seeds (their intervals are wider, honestly so).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.aside import in_own_process
from probecommit.runner.config import config_data, parse_config
from probecommit.studies.breadth import FAMILY_K, breadth_row, budget_curve, paper_config, quick_config
from probecommit.studies.explain.ex4_breadth import single_width
from probecommit.studies.pricing import break_even

COLUMNS = ("blind_bayes", "blind_robust", "probe_robust")


def scaled_config(config: Any, scale: float, *, engine: str | None = None, repeats: int | None = None) -> Any:
    """``config`` with its prior scaled by ``scale`` about the centre and its truths mapped with it.

    A truth at relative position ``r`` of the prior (``low + r (high - low)``) stays at ``r``.
    Raises ValueError when a scaled prior would reach a non-positive latent (every latent here is
    a positive physical quantity).
    """
    data = config_data(config)
    low, high = np.asarray(data["model"]["prior_low"], float), np.asarray(data["model"]["prior_high"], float)
    centre, half = (low + high) / 2, (high - low) / 2
    new_low, new_high = centre - scale * half, centre + scale * half
    if np.any(new_low <= 0):
        raise ValueError(f"{data['name']}: prior scale {scale:g} reaches a non-positive latent")
    data["model"]["prior_low"], data["model"]["prior_high"] = new_low.tolist(), new_high.tolist()
    truths = data["instances"].get("truths")
    if truths:
        data["instances"]["truths"] = (centre + scale * (np.asarray(truths, float) - centre)).tolist()
    if engine:
        data["simulator"]["engine"] = engine
    if repeats:
        data["repeats"] = int(repeats)
    data["name"] = f"{data['name']}_prior{scale:g}"
    return parse_config(data)


def row_and_prices(episodes: Any, family: str, boot: dict[str, Any]) -> dict[str, float]:
    """A Table II row's cells (with intervals) and the break-even prices of its curve."""
    row = breadth_row(episodes, family, FAMILY_K.get(family, 5), resamples=boot["resamples"], seed=boot["seed"])
    out = {f"{c}{s}": float(row[f"{c}{s}"]) for c in (*COLUMNS, "paired") for s in ("", "_lo", "_hi")}
    curve = budget_curve(episodes, family, resamples=2, seed=0).set_index(["method", "k"])["mean"]
    keys = (("blind_robust", 0), ("probe_robust", 2), ("probe_robust", 5))
    m0, m2, m5 = (float(curve.get(key, math.nan)) for key in keys)
    if not np.isnan([m0, m2, m5]).any():
        p = break_even(m0, m2, m5)
        out["price.blind_above"], out["price.five_below"] = p.blind_above, p.five_below
    return out


#: The stored sweep rows (``explain/results/``): what each scale's row and prices are computed from.
STORED = "breadth_prior_episodes.parquet"
#: The episode columns a Table II row and its prices read (``breadth_row``, ``budget_curve``).
ROW_COLUMNS = ("instance_id", "repeat", "k", "method", "realized", "status")


def compact(episodes: pd.DataFrame, family: str, scale: float) -> pd.DataFrame:
    """The rows a Table II row and its prices read: the blind arms at k = 0, Probe-Robust at the row's
    budget and at k = 2 and 5 (the prices), the columns ``ROW_COLUMNS``, tagged with family and scale."""
    probe_k = {2, 5, FAMILY_K.get(family, 5)}
    keep = ((episodes["method"].isin(["blind_bayes", "blind_robust"]) & (episodes["k"] == 0))
            | ((episodes["method"] == "probe_robust") & episodes["k"].isin(probe_k)))
    rows = episodes.loc[keep, [c for c in ROW_COLUMNS if c in episodes]].reset_index(drop=True)
    return rows.assign(family=family, scale=float(scale))


def sweep_family(family: str, scales: list[float], runs: Path, *, engine: str | None, repeats: int,
                 quick: bool) -> pd.DataFrame:
    """Each scale's stored rows for one family (runs under ``runs/breadth_prior/``, resumed when complete)."""
    from probecommit.process.memory import release_free_heap
    from probecommit.runner.study import run_study

    base = paper_config(family)
    if quick:
        base = quick_config(base)
    out = []
    for s in scales:
        config = scaled_config(base, s, engine=engine, repeats=None if quick else repeats)
        result = run_study(config, runs / "breadth_prior" / config.name, workers=1, threads=1)
        out.append(compact(result.episodes, family, s))
        del result
        # The blind arms' prior-sample losses ([actions, 10000]: 113 MB for darts) and their temporaries stay in
        # glibc's heap once freed (up to ``HEAP_TOP_BYTES``), so each run started above the last one's high-water
        # mark: the explain process grew from 560 to 1076 MB over the sweep (issue 42). Given back between runs.
        release_free_heap()
    return pd.concat(out, ignore_index=True)


def span_summary(rows: dict[float, dict[str, float]], paper: dict[str, float]) -> dict[str, float]:
    """Per paper cell: inside the span of our intervals over every scale; and the qualitative checks.

    ``paper`` maps a cell name (``blind_bayes``, ``price.five_below``, ...) to the paper's value.
    A price has no interval: its span is the range of our point prices.
    """
    out: dict[str, float] = {}
    for name, p in paper.items():
        if name.startswith("price."):
            values = [r[name] for r in rows.values() if name in r]
            lo, hi = (min(values), max(values)) if values else (math.nan, math.nan)
        else:
            lo, hi = min(r[f"{name}_lo"] for r in rows.values()), max(r[f"{name}_hi"] for r in rows.values())
        out[f"span.{name}.lo"], out[f"span.{name}.hi"] = lo, hi
        out[f"span.{name}.paper_inside"] = float(lo <= p <= hi)
    cells = [n for n in paper if not n.startswith("price.")]
    prices = [n for n in paper if n.startswith("price.")]
    out["cells_inside"] = float(sum(out[f"span.{n}.paper_inside"] for n in cells))
    out["cells"] = float(len(cells))
    out["prices_inside"] = float(sum(out[f"span.{n}.paper_inside"] for n in prices))
    out["prices"] = float(len(prices))
    out["min_paired_lo"] = min(r["paired_lo"] for r in rows.values())
    out["probing_reduces_everywhere"] = float(all(r["probe_robust"] < min(r["blind_bayes"], r["blind_robust"])
                                                  for r in rows.values()))
    return out


def paper_cells(family: str) -> dict[str, float]:
    """The paper's Table II cells of ``family`` and its break-even prices (in our units)."""
    from probecommit.studies.paper_values import PRINTED, value

    out = {c: value(f"tab:breadth.{family}.{c}") for c in COLUMNS if f"tab:breadth.{family}.{c}" in PRINTED}
    for kind in ("blind_above", "five_below"):
        key = f"T01-pricing.{kind}.{family}"
        if key in PRINTED:
            out[f"price.{kind}"] = value(key) * (1.0 if family == "hinge" else 0.01)
    return out


def frozen_row(root: Path, family: str) -> dict[str, float] | None:
    """The frozen study's row (s = 1, the paper's instance counts) and prices, when reproduced under ``root``."""
    return frozen_row_from(root / "breadth" / "results" / "results.json", root / "cost" / "results" / "results.json",
                           family)


def frozen_row_from(table: Path, cost: Path, family: str) -> dict[str, float] | None:
    """The frozen study's row and prices from the breadth and cost studies' ``results.json`` (a reproduction's
    or a publication's), or None when the breadth study has no such row."""
    import json

    if not table.is_file():
        return None
    row = json.loads(table.read_text())["results"]["table_II"].get(family)
    if row is None:
        return None
    out = {f"{c}{s}": float(row[f"{c}{s}"]) for c in (*COLUMNS, "paired") for s in ("", "_lo", "_hi")}
    if cost.is_file():
        prices = json.loads(cost.read_text())["results"]["prices"].get(family, {})
        out.update({f"price.{k}": float(prices[k]) for k in ("blind_above", "five_below") if k in prices})
    return out


def sweep_keys(stored: pd.DataFrame, frozen: dict[str, dict[str, float] | None], boot: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.breadth_prior`` from the stored sweep rows (``STORED``) and each family's
    frozen row (None: none, as in a quick run): each scale's row and prices, the span summary, the widths.
    The explain step and ``verify`` both call this."""
    out: dict[str, Any] = {"scales": [float(s) for s in stored["scale"].unique()]}
    for family, part in stored.groupby("family", sort=False):
        rows = {float(s): row_and_prices(one, str(family), boot) for s, one in part.groupby("scale", sort=False)}
        if frozen.get(str(family)) is not None:
            rows[1.0] = frozen[str(family)]
        for s, row in rows.items():
            out.update({f"{family}.s{s:g}.{k}": v for k, v in row.items()})
        out.update({f"{family}.{k}": v for k, v in span_summary(rows, paper_cells(str(family))).items()})
        out.update({f"{family}.{k}": v for k, v in single_width(rows, paper_cells(str(family))).items()})  # ex4
        out[f"{family}.widths"] = len(rows)
    return out


def sweep_families(families: list[str], scales: list[float], runs: Path, engines: dict[str, str], repeats: int,
                   quick: bool) -> pd.DataFrame:
    """Every family's stored sweep rows (:func:`sweep_family`), in family order. Run in a process of its own
    (``runner.aside.in_own_process``): its 24 runs' working memory (the blind arms' prior-sample losses, the runs'
    traces) took the explain process from about 410 to 658 MB (issue 42, target 4); their runs are on disk for
    the later steps that read them (ex4's cone, ex19's darts)."""
    return pd.concat([sweep_family(family, scales, runs, engine=engines.get(family), repeats=repeats, quick=quick)
                      for family in families], ignore_index=True)


def run(root: Path, runs: Path, cfg: dict[str, Any], boot: dict[str, Any], quick: bool) -> tuple[dict[str, Any], pd.DataFrame]:
    """Every family's prior sweep and its span summary: the keys of ``explain:results.breadth_prior`` and the
    stored rows they are computed from (``STORED``)."""
    suffix = "_quick" if quick else ""
    scales = [float(s) for s in cfg[f"breadth_prior_scales{suffix}"]]
    engines = cfg.get("breadth_prior_engines", {})
    families = cfg[f"breadth_prior_families{suffix}"]
    stored = in_own_process(sweep_families, families, scales, runs, engines, int(cfg["breadth_prior_repeats"]), quick)
    frozen = {family: None if quick else frozen_row(root, family) for family in families}
    return sweep_keys(stored, frozen, boot), stored
