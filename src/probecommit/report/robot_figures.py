"""Fig. 5 (b-d): the robot run and its replays under injected faults.

(b) aim error against taps, one point per episode (filled: the tool entered; open: it
did not), medians joined, the model's window as a band and the opening's half-width
dashed; (c) optimism and coverage of a boundary-faulted replay minus the deployed one,
paired over positions, 95 % band, filled where resolved; (d) the same under a narrowed
prior.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from probecommit.report.style import COLUMN, legend_above


def aim_error_figure(rows: pd.DataFrame, window: float | None = None, half_opening: float | None = None,
                     title: str | None = None):
    """Fig. 5b: aim error (mm) against taps, one column wide; legend above the axes. ``title`` labels the
    source (the simulated rig), under the axes."""
    fig, ax = plt.subplots(figsize=(COLUMN, 2.7))
    rng = np.random.default_rng(0)  # horizontal jitter only, for legibility
    entered = rows["entered"].fillna(0).astype(bool).to_numpy() if "entered" in rows else np.zeros(len(rows), bool)
    x = rows["k"].to_numpy() + rng.uniform(-0.15, 0.15, len(rows))
    y = rows["aim_error"].to_numpy()
    ax.scatter(x[entered], y[entered], s=9, color="C0", label="entered", zorder=3)
    ax.scatter(x[~entered], y[~entered], s=9, facecolors="none", edgecolors="C3", label="did not enter", zorder=3)
    med = rows.groupby("k")["aim_error"].median()
    ax.plot(med.index, med.to_numpy(), color="k", lw=1.0, label="median")
    if window is not None:
        ax.axhspan(0, window, color="C2", alpha=0.15, lw=0, label=f"model window ({window:.2f} mm)")
    if half_opening is not None:
        ax.axhline(half_opening, color="0.4", ls="--", lw=0.8, label=f"opening half-width ({half_opening:.1f} mm)")
    ax.set_xlabel("taps before the commit")
    ax.set_ylabel("aim error |a − x| (mm)")
    ax.set_xticks(sorted(int(k) for k in rows["k"].unique()))
    ax.set_ylim(bottom=0)
    legend_above(ax, ncol=2)
    fig.tight_layout(rect=(0, 0.06 if title else 0, 1, 1))
    if title:
        fig.suptitle(title, fontsize=7, y=0.01, va="bottom")
    return fig


def fault_sweep_figure(sweep: pd.DataFrame, xlabel: str, reference: float | None = None, reference_label: str = "",
                       title: str | None = None):
    """Fig. 5c/5d: faulted minus deployed optimism and coverage against fault size, 95 % bands; one column wide.
    ``title`` labels the source (the simulated rig), above the legend."""
    fig, axes = plt.subplots(1, 2, figsize=(COLUMN, 2.4))
    for ax, metric, panel in ((axes[0], "optimism", "Δ optimism eₖ"), (axes[1], "coverage", "Δ coverage")):
        x = sweep["size"].to_numpy()
        mid = sweep[f"delta_{metric}"].to_numpy()
        ax.fill_between(x, sweep[f"delta_{metric}_lo"], sweep[f"delta_{metric}_hi"], color="C0", alpha=0.2, lw=0, label="95% CI")
        ax.plot(x, mid, color="C0", lw=1.0)
        resolved = sweep[f"{metric}_resolved"].to_numpy(bool)
        ax.scatter(x[resolved], mid[resolved], color="C0", s=12, zorder=3, label="resolved")
        ax.scatter(x[~resolved], mid[~resolved], facecolors="white", edgecolors="C0", s=12, zorder=3, label="not resolved")
        ax.axhline(0, color="0.5", lw=0.6)
        if reference is not None:
            ax.axvline(reference, color="0.3", ls=":", lw=0.9, label=reference_label)
        ax.set_title(panel, loc="left")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("faulted − deployed")
    fig.supxlabel(xlabel, fontsize=8, y=0.02)  # one label for both panels: two would collide at this width
    top = 0.74 if title else 0.8
    fig.tight_layout(rect=(0, 0.03, 1, top))
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", bbox_to_anchor=(0.5, top), ncol=2, frameon=False)
    if title:
        fig.suptitle(title, fontsize=7, y=0.995, va="top")
    return fig


def sweep_caption(sweep: pd.DataFrame, what: str) -> str:
    """Caption of a fault sweep from its data."""
    n = int(sweep["episodes"].iloc[0]) if "episodes" in sweep.columns else None
    return (f"The recorded taps replayed under {what}: faulted minus deployed model, paired over positions"
            + (f" (n = {n} episodes per size)" if n else "") + "; band: 95% cluster-bootstrap interval; filled: resolved.")


def aim_error_caption(rows: pd.DataFrame) -> str:
    """Caption of the aim-error figure from its data (verify draws it again with the same caption)."""
    return (f"Aim error against taps, {len(rows)} episodes; filled points entered, open did not; black: medians; "
            "band: the model's window; dashed: the opening's half-width.")
