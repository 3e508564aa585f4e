"""Figures of the insertion study: fault signatures and the boundary scan."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from probecommit.report.figures import belief_density, save_figure  # noqa: E402
from probecommit.tasks.insertion.model import TIP_RADIUS_MM, half_gap  # noqa: E402


def fault_signatures(per_budget: pd.DataFrame, path: str | Path) -> Path:
    """Escape, coverage, optimism and failure over the budget for each fault (fault arms)."""
    metrics = [("escape", "support escape"), ("coverage", "episode coverage"), ("optimism", "optimism e_k"), ("failure", "failure")]
    fig, axes = plt.subplots(1, 4, figsize=(11, 2.8), dpi=150)
    styles = {"none": "k-", "noise": "C0--", "boundary": "C3-", "prior": "C1-", "particles": "C2-", "frame": "C4-"}
    for ax, (col, label) in zip(axes, metrics):
        for fault, group in per_budget.groupby("fault", sort=False):
            ax.plot(group["k"], group[col], styles.get(fault, "-"), marker="o", ms=3, lw=1.3, label=fault)
        ax.set_xlabel("taps k")
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return save_figure(fig, path)


def scan_figure(grid: pd.DataFrame, scans: pd.DataFrame, instance_id: str, delta: float, path: str | Path) -> Path:
    """(a) Scale-accurate section of the slot with the scanned readings and both model boundaries."""
    g = grid[grid.instance_id == instance_id]
    s = scans[scans.instance_id == instance_id]
    c = float(s["c"].iloc[0])
    hg = float(half_gap(c))
    fig, ax = plt.subplots(figsize=(6.4, 3.0), dpi=150)
    # Plate section: top at 0, slot of half-gap hg, floor at -15, chamfer of width delta at each edge.
    for sign in (-1, 1):
        edge = sign * hg
        outer = sign * (hg + delta)
        ax.fill([outer, sign * 9, sign * 9, edge, edge], [0, 0, -16, -16, -delta], color="0.85", lw=0)
        ax.plot([outer, edge, edge], [0, -delta, -15], color="0.3", lw=1)
        ax.plot([sign * 9, outer], [0, 0], color="0.3", lw=1)
    ax.plot([-hg, hg], [-15, -15], color="0.3", lw=1)
    ax.scatter(g["offset_from_hole"], g["reading"], s=8, color="C0", zorder=3, label="MuJoCo tap reading")
    for sign in (-1, 1):
        ax.axvline(sign * (hg - TIP_RADIUS_MM), color="C3", ls="--", lw=1, label="deployed boundary hg - r" if sign < 0 else None)
        ax.axvline(sign * float(s[s.side == ("left" if sign < 0 else "right")]["boundary"].iloc[0]), color="C2", lw=1.2,
                   label="scanned boundary" if sign < 0 else None)
    ax.set_xlim(-8, 8)
    ax.set_ylim(-17, 2)
    ax.set_xlabel("tap offset from hole centre (mm)")
    ax.set_ylabel("reading (mm)")
    ax.set_title(f"{instance_id}: c = {c:.2f}, hg = {hg:.2f} mm; boundary moves {delta + TIP_RADIUS_MM:.2f} mm", fontsize=8)
    ax.legend(fontsize=7, loc="lower left", frameon=False)
    fig.tight_layout()
    return save_figure(fig, path)


def decisive_tap_figure(z_deployed, w_deployed, z_corrected, w_corrected, z_true: float, tap: float, reading: float,
                        title: str, path: str | Path) -> Path:
    """(b) Beliefs under the deployed and the corrected model right after the decisive tap."""
    grid = np.linspace(-11, 11, 700)
    fig, ax = plt.subplots(figsize=(6.4, 2.6), dpi=150)
    ax.plot(grid, belief_density(z_deployed, w_deployed, grid, 0.3), color="C3", label="deployed model")
    ax.plot(grid, belief_density(z_corrected, w_corrected, grid, 0.3), color="C2", label="corrected model")
    ax.axvline(z_true, color="k", ls="--", lw=1, label="true hole")
    ax.axvline(tap, color="C0", ls=":", lw=1.2, label=f"tap at {tap:+.1f} mm read {reading:.1f} mm")
    ax.set_xlabel("hole position (mm)")
    ax.set_ylabel("belief (peak-normalized)")
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return save_figure(fig, path)
