"""The insertion study's Markdown tables, each a pure function of its results and stored tables.

Why: the reproduction writes these tables and ``verify`` renders them again from the stored
``results.json`` (and the stored Parquet tables) and compares the text, so an edit to a
published table, a rounding changed, a row swapped or a number moved, fails. One function
per table; nothing here computes a statistic.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

TITLES = {
    "scan": "Boundary scan on the development truths",
    "table_IV_insertion": "Insertion failure by split and calibration setting (MuJoCo)",
    "table_III_audit": "Insertion audit, Split B, random probes (MuJoCo)",
    "table_V_testc": "Confirmation on untouched instances (Test C), MuJoCo",
    "gates": "Commit gates, Split B, cover schedule (failure among committed vs commit rate)",
    "table_I_setup_insertion": "Experimental setup, insertion (MuJoCo)",
}


def fmt(v: Any, signed: bool = False) -> str:
    if isinstance(v, (list, tuple)) and len(v) == 3:
        return f"{v[0]:+.3f} [{v[1]:+.3f}, {v[2]:+.3f}]" if signed else f"{v[0]:.3f} [{v[1]:.3f}, {v[2]:.3f}]"
    if isinstance(v, float):
        return f"{v:+.3f}" if signed else f"{v:.3f}"
    return str(v)


def md_table(header: list[str], rows: list[list[Any]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def page(title: str, table: str, note: str = "") -> str:
    """A table file: heading, table, optional note."""
    return f"### {title}\n\n{table}\n" + (f"\n{note}\n" if note else "")


def scan(r: dict[str, Any], folder: Path) -> str:
    s = r["scan"]
    return page(TITLES["scan"], md_table(
        ["scans", "delta mean (mm)", "SD", "min", "max", "shift vs deployed hg - r (mm)", "frozen delta"],
        [[s["scans"], f"{s['delta']:+.4f}", f"{s['sd']:.4f}", f"{s['min']:+.4f}", f"{s['max']:+.4f}",
          f"{s['shift_vs_deployed_mm']:.3f}", f"{s['frozen_delta']:+.3f}"]]))


def cover_search(r: dict[str, Any], folder: Path) -> str:
    table = pd.read_parquet(folder / "cover_search.parquet")
    top = table.head(5)
    rows = [[i + 1, str([float(u) for u in json.loads(str(row["schedule"]))]), f"{row['failure']:.3f}",
             f"{row['aim_error']:.2f}"] for i, row in top.iterrows()]
    return page(f"Cover-schedule search ({len(table)} subsets, development instances, k = 5)",
                md_table(["rank", "schedule (mm)", "failure", "mean aim error (mm)"], rows))


def _cost_row(row: dict[str, Any]) -> list[str]:
    k = int(row["k"])
    label = {"blind_robust": ("Blind-Robust", "--", "--"), "no calibration": (f"cover, k={k}", "no", "no"),
             "set calibration": (f"cover, k={k}", "yes", "no"),
             "set calibration + margin": (f"cover, k={k}", "yes", "yes")}[str(row["setting"])]
    return [*label, fmt([float(row["failure"]), float(row["failure_lo"]), float(row["failure_hi"])])]


def table_IV_insertion(r: dict[str, Any], folder: Path) -> str:
    res = r["table_insertion"]
    rows = [["A", "no probe (Blind-Bayes)", "--", "--", fmt(res["A.no_probe"])],
            ["A", "cover, k=5", "no", "no", fmt(res["A.cover_k5"])]]
    rows += [["B", *_cost_row(row)] for row in res["B.cost_table"]]
    thresholds = {int(k): round(v, 3) for k, v in res["thresholds_cover"].items()}
    note = (f"Margin gamma (cover) = {res['margin_cover']}; conformal t_k (cover) = {thresholds}; "
            f"distribution-free margin = {res['distribution_free_margin_cover']:.3f}.")
    return page(TITLES["table_IV_insertion"], md_table(["split", "method", "set cal.", "margin", "failure [95% CI]"], rows),
                note)


def table_III_audit(r: dict[str, Any], folder: Path) -> str:
    records, summary, esc = r["table_audit"]["table"], r["table_audit"]["summary"], r["text"]
    cols = [c for c in records[0] if not c.endswith(("_lo", "_hi"))]
    rows = [[fmt(rec[c]) if isinstance(rec[c], float) else rec[c] for c in cols] for rec in records]
    note = (f"Summary: {json.dumps({k: round(float(v), 3) for k, v in summary.items()})}. "
            f"Escape k=1: {fmt(esc['escape_k1'])}, k=8: {fmt(esc['escape_k8'])}; "
            f"episode coverage k=1: {fmt(esc['episode_coverage_k1'])}, k=8: {fmt(esc['episode_coverage_k8'])}.")
    return page(TITLES["table_III_audit"], md_table(cols, rows), note)


def table_V_testc(r: dict[str, Any], folder: Path) -> str:
    res = r["table_testc"]
    rows = []
    for key, row in res.items():
        if key == "failure_cover_k5_setcal_margin":
            fo, fn = row["old"], row["corrected"]
            rows.append([key, fmt(fo), fmt(fn), fmt(row["old_minus_corrected"], signed=True) if "old_minus_corrected" in row
                         else f"{fo - fn:+.3f}" if isinstance(fo, float) else "--"])
        else:
            rows.append([key, fmt(row["old"][0]), fmt(row["corrected"][0]), fmt(row["old_minus_corrected"], signed=True)])
    return page(TITLES["table_V_testc"], md_table(["row", "old", "corrected", "old - corrected [95% CI]"], rows),
                "Both models see identical taps; paired cluster bootstrap over instances.")


def table_VIII_faults(r: dict[str, Any], folder: Path) -> str:
    res, setup = r["table_faults"], r["setup"]
    rows = []
    for fault, row in res.items():
        auc = row.get("surprise_auc")
        rows.append([fault, fmt(row["fail"]), f"{auc:.2f}" if auc is not None else "--",
                     fmt(row["tempered"][0]) if "tempered" in row else "--", fmt(row["fix"][0]) if "fix" in row else "--",
                     fmt(row["paired_fix"], signed=True) if "paired_fix" in row else "--"])
    kmax = setup["k_random"]
    return page(f"Controlled mismatch tests, random probes, k = {kmax} (MuJoCo)", md_table(
        ["fault", "fail [95% CI]", "surprise AUC", f"tempered T={setup['temperature']:g}", "known fix",
         "fix - fault (paired)"], rows))


def robust(r: dict[str, Any], folder: Path) -> str:
    res, kmax = r["robust"], r["setup"]["k_random"]
    d = res["deployed"]
    rows = [["deployed (no robust filter)", "--", fmt(d["escape"][0]), fmt(d["failure"][0]), fmt(d["optimism"][0], signed=True),
             "--"]]
    for family in res["chosen"]:
        m = res[family]
        rows.append([family, f"{m['value']:g}", fmt(m["escape"][0]), fmt(m["failure"][0]), fmt(m["optimism"][0], signed=True),
                     fmt(m["failure_diff"], signed=True)])
    cost = res.get("mixture_cost_when_right")
    note = (f"Chosen on the development instances by lowest k = {kmax} failure under the deployed model. "
            + (f"When the model is right the mixture moves failure {cost[0]:.3f} -> {cost[1]:.3f}." if cost else ""))
    return page(f"Robust filters under the boundary error, random k = {kmax} (MuJoCo)",
                md_table(["filter", "chosen", "escape", "failure", "optimism", "failure vs deployed (paired)"], rows), note)


def resplits(r: dict[str, Any], folder: Path) -> str:
    s = r["resplits"]
    return page(f"{s['splits']} random re-splits of one {s['pool']}-instance pool (cover, k = 5)", md_table(
        ["calibrated level t_5 (mean +- SD)", "failure set+margin (mean +- SD)", "held-out cluster coverage",
         "margin optimistic"],
        [[f"{s['level_mean_sd'][0]:.3f} +- {s['level_mean_sd'][1]:.3f}",
          f"{s['failure_mean_sd'][0]:.3f} +- {s['failure_mean_sd'][1]:.3f}",
          f"{s['heldout_cluster_coverage']:.3f}", s["margin_optimistic_fraction"]]]))


def gates(r: dict[str, Any], folder: Path) -> str:
    summary = pd.DataFrame(r["gates"]["summary"])
    cols = [c for c in summary.columns if summary[c].dtype != object or c == "signal"]
    rows = [[fmt(v) if isinstance(v, float) else v for v in row] for row in summary[cols].itertuples(index=False)]
    return page(TITLES["gates"], md_table(cols, rows))


def table_I_setup_insertion(r: dict[str, Any], folder: Path) -> str:
    s = r["setup"]
    return page(TITLES["table_I_setup_insertion"], md_table(
        ["family", "engine", "latents", "probe / action", "sigma", "budgets k", "n; metric"],
        [["insertion", s["engine"], "x_hole, c", "tap / aim", f"{s['sigma']} mm",
          f"1-{s['k_random']}, cover {list(s['cover_schedule'])}", f"{s['n']}; failure"]]))


#: Table file (without suffix, named by the paper's numbering) -> its renderer.
RENDERERS = {"scan": scan, "cover_search": cover_search, "table_IV_insertion": table_IV_insertion,
             "table_III_audit": table_III_audit, "table_V_testc": table_V_testc, "table_VIII_faults": table_VIII_faults,
             "robust": robust, "resplits": resplits, "gates": gates, "table_I_setup_insertion": table_I_setup_insertion}
