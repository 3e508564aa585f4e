"""The keys of E112..E114 from their stored rows (what the explain step publishes and verify recomputes).

The rows (``ex14_escape.READINGS`` x trajectories x budgets) carry, per reading, escape as that reading
measures it and the belief's retained coverage, realized failure and score (for ``prejitter``, a
measurement reading, the stated belief's), the running-max surprise and, at k = 1, whether the first tap
lay in the misread band. ``run`` is ``random`` (Table III's Split B random test) or ``cover`` (T36's
paper's-schedule Split B test).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.metrics import audit_table
from probecommit.audit.stats import cluster_bootstrap_auc, cluster_bootstrap_mean
from probecommit.studies.explain.ex14_escape import READINGS

#: The stored rows of all three groups.
STORED = "ex14_escape_rows.parquet"


def _triple(out: dict[str, Any], name: str, iv: Any) -> None:
    out[name], out[f"{name}_lo"], out[f"{name}_hi"] = float(iv.estimate), float(iv.lo), float(iv.hi)


def escape_keys(rows: pd.DataFrame, p_band: float, paper_k1: float, paper_k8: float, boot: dict[str, int]) -> dict[str, Any]:
    """E112: the exact band probability, the observed band share, the paper's implied P(escape | band), and
    per reading escape at k = 1 and 8 (cluster-bootstrap), its k = 1 split by band, and whether the paper's
    two escapes both lie inside its intervals; ``selected`` is the first such reading after ``stated``
    (1-based index into ``READINGS``; 0: none)."""
    r = rows[rows["run"] == "random"]
    first = r[(r["reading"] == READINGS[0]) & (r["k"] == 1)]
    out: dict[str, Any] = {"p_band": float(p_band), "band_share": float(first["in_band"].mean()),
                           "implied_escape_given_band": float(paper_k1 / p_band)}
    selected = 0
    for i, reading in enumerate(READINGS):
        part = r[r["reading"] == reading]
        for k in (1, 8):
            at = part[part["k"] == k]
            _triple(out, f"{reading}.escape_k{k}", cluster_bootstrap_mean(
                at["escaped"].to_numpy(float), at["instance_id"].to_numpy(), **boot))
        k1 = part[part["k"] == 1]
        band = k1["in_band"].to_numpy(bool)
        esc = k1["escaped"].to_numpy(bool)
        out[f"{reading}.escape_given_band_k1"] = float(esc[band].mean()) if band.any() else float("nan")
        out[f"{reading}.escape_off_band_k1"] = float(esc[~band].mean()) if (~band).any() else float("nan")
        ok = all(out[f"{reading}.escape_k{k}_lo"] <= p <= out[f"{reading}.escape_k{k}_hi"]
                 for k, p in ((1, paper_k1), (8, paper_k8)))
        out[f"{reading}.reproduces"] = int(ok)
        if ok and i > 0 and not selected:
            selected = i + 1
    out["n_reproducing"] = int(sum(out[f"{x}.reproduces"] for x in READINGS[1:]))
    out["selected"] = int(selected)
    return out


def draw_keys(rows: pd.DataFrame) -> dict[str, Any]:
    """Beside E112: per fresh draw (``run`` = ``draw_NN``), the band share of first taps, P(escape | band) and
    k = 1 escape; min and max over the draws (``draws.n`` = 0 and NaN when there are none)."""
    d = rows[rows["run"].astype(str).str.startswith("draw_")]
    per = []
    for _, part in d.groupby("run"):
        band, esc = part["in_band"].to_numpy(bool), part["escaped"].to_numpy(bool)
        per.append((band.mean(), esc[band].mean() if band.any() else np.nan, esc.mean()))
    out: dict[str, Any] = {"draws.n": len(per)}
    for i, name in enumerate(("band_share", "escape_given_band_k1", "escape_k1")):
        values = np.array([p[i] for p in per], float)
        finite = values[np.isfinite(values)]
        out[f"draws.{name}.min"] = float(finite.min()) if finite.size else float("nan")
        out[f"draws.{name}.max"] = float(finite.max()) if finite.size else float("nan")
    return out


def audit_keys(rows: pd.DataFrame, budgets: Sequence[int], boot: dict[str, int]) -> dict[str, Any]:
    """E113: per reading, Table III's original cells (cluster coverage, optimism per budget, cluster-bootstrap)
    and mean |optimism|, and optimism split by stratum: escape share, realized minus score on escaped and
    on the rest (optimism = share x gap_escaped + (1 - share) x gap_covered)."""
    out: dict[str, Any] = {}
    r = rows[rows["run"] == "random"]
    for reading in READINGS:
        part = r[(r["reading"] == reading) & r["k"].isin(list(budgets))]
        table = part.assign(method="probe_robust", variant="deployed", status="ok")
        audit = audit_table(table, **boot).sort_values("k")
        for row in audit.itertuples():
            for m in ("cluster_coverage", "optimism"):
                for s in ("", "_lo", "_hi"):
                    out[f"{reading}.{m}{s}.k{int(row.k)}"] = float(getattr(row, f"{m}{s}"))
        out[f"{reading}.mean_abs_optimism"] = float(np.mean(np.abs(audit["optimism"].to_numpy(float))))
        for k, at in part.groupby("k"):
            esc = at["escaped"].to_numpy(bool)
            gap = at["realized"].to_numpy(float) - at["predicted"].to_numpy(float)
            out[f"{reading}.escape_share.k{int(k)}"] = float(esc.mean())
            out[f"{reading}.gap_escaped.k{int(k)}"] = float(gap[esc].mean()) if esc.any() else 0.0
            out[f"{reading}.gap_covered.k{int(k)}"] = float(gap[~esc].mean()) if (~esc).any() else 0.0
    return out


def surprise_keys(rows: pd.DataFrame, budgets: tuple[int, int], boot: dict[str, int]) -> dict[str, Any]:
    """E114: per reading, T36's escapes (outside the hull at the final budget, as the reading measures it) and
    the running-max surprise AUC at the first and final budget (cluster bootstrap)."""
    out: dict[str, Any] = {}
    first, final = budgets
    c = rows[rows["run"] == "cover"]
    for reading in READINGS:
        part = c[c["reading"] == reading]
        w = part.pivot_table(index=["instance_id", "repeat"], columns="k", values=["max_surprise", "escaped"])
        y = w[("escaped", final)].astype(bool).to_numpy()
        ids = w.index.get_level_values(0).to_numpy()
        out[f"{reading}.n"], out[f"{reading}.n_escaped"] = int(len(y)), int(y.sum())
        for k in budgets:
            _triple(out, f"{reading}.auc_k{k}", cluster_bootstrap_auc(w[("max_surprise", k)].to_numpy(float), y, ids, **boot))
    return out
