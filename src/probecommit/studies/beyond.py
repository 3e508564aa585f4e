"""Beyond the paper: the hull set at t = 1, the resample-move belief, adaptive probes.

Each comparison replays or recalibrates existing run directories (identical probes
for both arms where the probes do not depend on the belief), so the numbers in
``docs/beyond-the-paper.md`` come from this module and the frozen configs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import pandas as pd

from probecommit.runner.calibration import calibrate
from probecommit.runner.replay import load_run, replay_episodes


def move_comparison(runs: Mapping[str, str | Path], budget: int = 8) -> pd.DataFrame:
    """Escape, coverage, optimism and failure at ``budget`` under the paper's jitter and under MH.

    Args:
        runs: Label -> run directory (random probes; both arms replay the stored taps).
        budget: The probe budget compared.

    Returns:
        One row per (run, move).
    """
    rows = []
    for label, path in runs.items():
        loaded = load_run(path)
        for move in ("jitter", "mh"):
            episodes, _ = replay_episodes(loaded, {"belief": {"move": move}})
            p = episodes[(episodes["method"] == "probe_robust") & (episodes["k"] == budget) & (episodes["status"] == "ok")]
            rows.append({
                "run": label, "move": move, "n": len(p), "escape": p["escaped"].mean(),
                "episode_coverage": p["covered"].mean(), "optimism": p["realized"].mean() - p["predicted"].mean(),
                "failure": p["realized"].mean(),
            })
    return pd.DataFrame(rows)


def plateau_comparison(cal_run: str | Path, test_run: str | Path, resamples: int = 2000) -> pd.DataFrame:
    """Calibrated cluster coverage and optimism per budget with the paper's prefix set and the hull set at t = 1."""
    parts = []
    for mode in ("prefix", "hull"):
        result = calibrate(cal_run, test_run, plateau=mode, resamples=resamples)
        table = result.table3[["k", "threshold", "cluster_coverage_calibrated", "optimism_calibrated"]].copy()
        table.insert(0, "plateau", mode)
        parts.append(table)
    return pd.concat(parts, ignore_index=True)
