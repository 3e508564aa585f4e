"""Figures (matplotlib, Agg backend; no display needed)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def save_figure(fig, path: str | Path, dpi: int | None = None) -> Path:
    """Write ``fig`` to ``path`` and close it (figures are built in loops; open ones leak)."""
    path = Path(path)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def belief_density(z: np.ndarray, weights: np.ndarray, grid: np.ndarray, bandwidth: float) -> np.ndarray:
    """Weighted Gaussian-kernel density of particles on ``grid``, peak-normalized."""
    diff = (grid[:, None] - z[None, :]) / bandwidth
    dens = np.exp(-0.5 * diff * diff) @ weights
    peak = dens.max()
    return dens / peak if peak > 0 else dens


def belief_snapshots(
    trace,
    model,
    episodes: pd.DataFrame,
    episode_row: int,
    budgets: Sequence[int],
    path: str | Path,
    title: str | None = None,
) -> Path:
    """Peak-normalized beliefs over the decision coordinate after chosen budgets (Fig. 1b).

    Args:
        trace: A ``BeliefTrace`` holding the episode.
        model: The model (decision coordinate, action grid).
        episodes: Episode rows of that trace (to mark each budget's committed aim).
        episode_row: Row of the episode within the trace batch.
        budgets: Budgets to draw, e.g. ``(1, 3, 5)``.
        path: Output PNG.
    """
    batch = trace.batch
    iid, rep = str(batch.instance_id[episode_row]), int(batch.repeat[episode_row])
    z_true = float(model.decision(batch.truths[episode_row]))
    lo, hi = float(model.prior_low[0]), float(model.prior_high[0])
    grid = np.linspace(lo - 1, hi + 1, 600)
    colors = plt.cm.viridis(np.linspace(0.15, 0.85, len(budgets)))
    fig, ax = plt.subplots(figsize=(6.4, 3.0), dpi=150)
    for color, k in zip(colors, budgets):
        state = trace.states[k]
        z = model.decision(state.particles[episode_row])
        ax.plot(grid, belief_density(z, state.weights[episode_row], grid, 0.3), color=color, lw=1.6, label=f"after tap {k}")
        row = episodes[(episodes.instance_id == iid) & (episodes.repeat == rep) & (episodes.k == k) & (episodes.method == "probe_robust")]
        if len(row):
            aim = float(row["action"].iloc[0])
            ok = float(row["realized"].iloc[0]) == 0
            ax.plot([aim], [1.08], marker="v", ms=8, color=color, markerfacecolor=color if ok else "white")
    ax.axvline(z_true, color="crimson", ls="--", lw=1.2, label="true hole")
    taps = batch.u[episode_row, : max(budgets)]
    ax.plot(taps, np.full_like(taps, -0.06), "k|", ms=10, label="tap positions")
    ax.set_xlim(grid[0], grid[-1])
    ax.set_ylim(-0.12, 1.18)
    ax.set_xlabel("hole position x_hole (mm)")
    ax.set_ylabel("belief (peak-normalized)")
    ax.set_title(title or f"{iid}, repeat {rep}: beliefs and aims (filled: entered, open: failed)", fontsize=8)
    ax.legend(fontsize=7, loc="upper left", frameon=False)
    fig.tight_layout()
    return save_figure(fig, path)
