"""Figures of the insertion study: fault signatures and the boundary scan."""

from __future__ import annotations

from pathlib import Path

import matplotlib

from probecommit.report.backend import use_agg_unless_chosen  # noqa: E402

use_agg_unless_chosen()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit.report.figures import belief_density, save_figure  # noqa: E402
from probecommit.report.style import COLUMN, integer_ticks  # noqa: E402
from probecommit.tasks.insertion.model import TIP_RADIUS_MM, half_gap  # noqa: E402


#: Fault classes: one colour, line style and marker each (overlapping series stay distinguishable).
FAULT_STYLES = {"none": ("k", "-", "o"), "noise": ("C0", (0, (4, 2)), "x"), "boundary": ("C3", "-", "s"),
                "prior": ("C1", "-.", "^"), "particles": ("C2", ":", "D"), "frame": ("C4", (0, (1, 1)), "v")}


def fault_signatures(per_budget: pd.DataFrame, path: str | Path, n: int | None = None) -> Path:
    """The fault classes over the probe budget: support escape, coverage, optimism and failure (fault arms).

    One column wide, 2 x 2 panels; ``n`` (episodes per point) goes into the caption.
    """
    metrics = [("escape", "(a) support escape", "support escape"), ("coverage", "(b) coverage", "coverage"),
               ("optimism", "(c) optimism", "optimism eₖ"), ("failure", "(d) realized failure", "realized Rₖ")]
    fig, axes = plt.subplots(2, 2, figsize=(COLUMN, 3.9), sharex=True)
    faults = list(dict.fromkeys(per_budget["fault"]))
    for ax, (col, title, ylabel) in zip(axes.ravel(), metrics):
        for i, (fault, group) in enumerate(per_budget.groupby("fault", sort=False)):
            color, ls, marker = FAULT_STYLES.get(fault, ("0.4", "-", "o"))
            # a small horizontal offset per fault: noise and frame coincide with "none" at times
            offset = (i - (len(faults) - 1) / 2) * 0.06
            ax.plot(group["k"] + offset, group[col], color=color, ls=ls, marker=marker, ms=2.5, lw=0.9,
                    markerfacecolor="none" if fault in ("noise", "frame") else color, label=fault)
            if f"{col}_lo" in group.columns:  # the cluster-bootstrap band
                ax.fill_between(group["k"] + offset, group[f"{col}_lo"], group[f"{col}_hi"], color=color, alpha=0.10, lw=0)
        ax.set_title(title, loc="left")
        ax.set_ylabel(ylabel)
        integer_ticks(ax.xaxis)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("budget k (taps)")
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="lower center", ncol=3, frameon=False,
               bbox_to_anchor=(0.5, 0.9), handlelength=2.2, columnspacing=1.0)
    kmin, kmax = int(per_budget["k"].min()), int(per_budget["k"].max())
    caption = (f"The fault classes over the probe budget (k = {kmin}..{kmax}), fault arms, Probe-Robust"
               + (f", n = {n} episodes per point" if n else "") + "; bands: 95% cluster-bootstrap intervals over instances.")
    return save_figure(fig, path, caption=caption)


def scan_figure(grid: pd.DataFrame, scans: pd.DataFrame, instance_id: str, delta: float, path: str | Path) -> Path:
    """(a) Scale-accurate section of the slot with the scanned readings and both model boundaries."""
    g = grid[grid.instance_id == instance_id]
    s = scans[scans.instance_id == instance_id]
    c = float(s["c"].iloc[0])
    hg = float(half_gap(c))
    fig, ax = plt.subplots(figsize=(COLUMN, 3.0))
    ax.set_aspect("equal")  # to scale: one mm is one mm in both directions
    # Plate section: top at 0, slot of half-gap hg, floor at -15, chamfer of width delta at each edge.
    for sign in (-1, 1):
        edge = sign * hg
        outer = sign * (hg + delta)
        ax.fill([outer, sign * 9, sign * 9, edge, edge], [0, 0, -16, -16, -delta], color="0.85", lw=0)
        ax.plot([outer, edge, edge], [0, -delta, -15], color="0.3", lw=1)
        ax.plot([sign * 9, outer], [0, 0], color="0.3", lw=1)
    ax.plot([-hg, hg], [-15, -15], color="0.3", lw=1)
    ax.annotate("pocket floor", (0, -15), xytext=(0, -3), textcoords="offset points", ha="center", va="top", fontsize=7)
    ax.scatter(g["offset_from_hole"], g["reading"], s=4, color="C0", zorder=3, label="tap reading (engine)")
    # The simulated probe path of two taps beside the edge: down to the plate top outside the
    # scanned boundary; down the chamfer and into the slot inside it (tip centre, radius r).
    right = float(s[s.side == "right"]["boundary"].iloc[0])
    theta_circle = np.linspace(0, 2 * np.pi, 40)
    for u, inside in ((right + 0.4, False), (right - 0.3, True)):
        end_x = u if not inside else min(u, hg - TIP_RADIUS_MM)
        end_z = TIP_RADIUS_MM if not inside else -15 + TIP_RADIUS_MM
        path_x = [u, u] if not inside else [u, u, hg - TIP_RADIUS_MM * 0.3, end_x, end_x]
        path_z = [8, end_z] if not inside else [8, TIP_RADIUS_MM * 0.7 - (u - hg) * 0 , -delta, -delta - 1, end_z]
        ax.plot(path_x, path_z, color="C3" if inside else "0.5", lw=0.8, ls=":")
        ax.plot(end_x + TIP_RADIUS_MM * np.cos(theta_circle), end_z + TIP_RADIUS_MM * np.sin(theta_circle),
                color="C3" if inside else "0.5", lw=0.8)
    for sign in (-1, 1):
        ax.axvline(sign * (hg - TIP_RADIUS_MM), color="C3", ls="--", lw=1, label="deployed boundary hg − r" if sign < 0 else None)
        ax.axvline(sign * float(s[s.side == ("left" if sign < 0 else "right")]["boundary"].iloc[0]), color="C2", lw=1.2,
                   label="scanned boundary" if sign < 0 else None)
    ax.set_xlim(-9, 9)
    ax.set_ylim(-19, 10)
    ax.set_xlabel("tap offset from hole centre (mm)")
    ax.set_ylabel("height (mm)")
    ax.set_title(f"c = {c:.2f}: the boundary moves {delta + TIP_RADIUS_MM:.2f} mm")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False, ncol=2, fontsize=7)
    fig.tight_layout()
    caption = (f"Scale-accurate section of the slot (c = {c:.2f}, chamfer {delta:.2f} mm) with {len(g)} engine tap readings; "
               "dashed: the analytic model's boundary hg − r; solid: the scanned boundary; dotted: two simulated probe paths.")
    return save_figure(fig, path, caption=caption)


def decisive_tap_figure(z_deployed, w_deployed, z_corrected, w_corrected, z_true: float, tap: float, reading: float,
                        title: str, path: str | Path) -> Path:
    """(b) Beliefs under the deployed and the corrected model right after the decisive tap."""
    grid = np.linspace(-11, 11, 700)
    fig, ax = plt.subplots(figsize=(COLUMN, 2.6))
    ax.plot(grid, belief_density(z_deployed, w_deployed, grid, 0.3), color="C3", label="deployed model")
    ax.plot(grid, belief_density(z_corrected, w_corrected, grid, 0.3), color="C2", label="corrected model")
    ax.axvline(z_true, color="k", ls="--", lw=1, label="true hole")
    ax.axvline(tap, color="C0", ls=":", lw=1.2, label=f"tap at {tap:+.1f} mm read {reading:.1f} mm")
    ax.set_xlabel("hole position (mm)")
    ax.set_ylabel("belief (peak-normalized)")
    ax.set_ylim(0, 1.05)
    if title:
        ax.set_title(title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.28), frameon=False, ncol=2, handlelength=1.6)
    fig.tight_layout()
    caption = (f"Beliefs (peak-normalized kernel density of the particles) right after the tap at {tap:+.1f} mm, which "
               f"read {reading:.1f} mm; true hole at {z_true:+.2f} mm.")
    return save_figure(fig, path, caption=caption)


def decision_figure(coverage: pd.DataFrame, gates_result, path: str | Path) -> Path:
    """Fig. "commit decision" at one column: (a) cluster coverage vs nominal, (b) failure among
    committed vs commit rate (the oracle dashed), (c) predicted (pale) vs realized (solid) at the operating point."""
    from probecommit.report.audit_report import draw_gate_curves, draw_gate_operating_point

    fig = plt.figure(figsize=(COLUMN, 4.6))
    grid = fig.add_gridspec(2, 2, width_ratios=[1, 1.35], height_ratios=[1.25, 1])
    ax_a = fig.add_subplot(grid[0, 0])
    ax_a.plot([0.5, 1.0], [0.5, 1.0], color="grey", ls=":", lw=1, label="nominal")
    ax_a.plot(coverage["nominal"], coverage["cluster_coverage"], "o-", color="C0", ms=3, label="held-out")
    ax_a.set_xlabel("nominal level 1 − α")
    ax_a.set_ylabel("cluster coverage")
    ax_a.set_title("(a) coverage", loc="left")
    ax_a.legend(frameon=False, loc="upper left", handlelength=1.2)
    ax_b = fig.add_subplot(grid[0, 1])
    draw_gate_curves(ax_b, gates_result.curves, legend=False)
    ax_b.set_xlabel("commit rate")
    ax_b.set_title("(b) failure vs commit rate", loc="left")
    ax_c = fig.add_subplot(grid[1, :])
    draw_gate_operating_point(ax_c, gates_result.summary)
    ax_c.set_title("(c) at the operating point", loc="left")
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    handles, labels = ax_b.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, 0.9), ncol=2, frameon=False, handlelength=2.4)
    summary = gates_result.summary
    n = (int(summary["n_committed"].iloc[0] + summary["n_rejected"].iloc[0])
         if {"n_committed", "n_rejected"} <= set(summary.columns) else None)
    rate = float(summary["commit_rate"].iloc[0]) if "commit_rate" in summary.columns else None
    caption = ("Commit-decision audit. (a) Held-out cluster coverage against the nominal level 1 − α. (b) Failure among "
               "committed episodes against commit rate, first-passage commitment over nested budgets"
               + (f", n = {n} test trajectories" if n else "") + "; dashed: the non-deployable hindsight oracle. (c) "
               + (f"At {rate:.0%} commitment, " if rate is not None else "At the operating point, ")
               + "mean predicted score (pale) against realized failure (solid); posterior variance makes no probability claim.")
    return save_figure(fig, path, caption=caption)


def draw_decisive_tap(series: pd.DataFrame, path: Path) -> Path:
    """Fig. 4b from its data series (the study and verify draw it by this call)."""
    part = {name: rows for name, rows in series.groupby("model", sort=False)}
    first = series.iloc[0]
    return decisive_tap_figure(part["deployed"]["z"].to_numpy(), part["deployed"]["weight"].to_numpy(),
                               part["corrected"]["z"].to_numpy(), part["corrected"]["weight"].to_numpy(),
                               float(first["z_true"]), float(first["tap"]), float(first["reading"]),
                               f"after tap {int(first['k'])}", path)  # no internal ids in a title
