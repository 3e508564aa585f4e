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
from probecommit.store.safefile import write_text, write_with


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


def budget_summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """Failure (or miss), coverage, escape and optimism per budget of the probe-robust rows."""
    p = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    grouped = p.groupby("k")
    return pd.DataFrame({
        "n": grouped.size(),
        "realized": grouped["realized"].mean(),
        "predicted": grouped["predicted"].mean(),
        "optimism": grouped["realized"].mean() - grouped["predicted"].mean(),
        "episode_coverage": grouped["covered"].mean(),
        "escape": grouped["escaped"].mean(),
        "post_var": grouped["post_var"].mean(),
    }).reset_index()


def adaptive_comparison(runs: Mapping[str, str | Path], out: str | Path, workers: int = 1) -> pd.DataFrame:
    """Run each given run's config again with ``schedule: adaptive`` and compare per budget.

    Args:
        runs: Label -> a complete run directory with random or scheduled probes (its
            config, instances and seeds are reused; only the schedule changes).
        out: Folder for the adaptive runs (``<out>/<label>-adaptive``).
        workers: Local worker processes.

    Returns:
        One row per (label, schedule, k).
    """
    from probecommit.runner.config import config_data, parse_config
    from probecommit.runner.study import run_study

    rows = []
    for label, path in runs.items():
        loaded = load_run(path)
        data = config_data(loaded.config)
        data["name"] = f"{data['name']}-adaptive"
        data["probes"] = {**data["probes"], "schedule": "adaptive"}
        adaptive = run_study(parse_config(data), Path(out) / f"{label}-adaptive", workers=workers)
        schedule = loaded.config.probes.schedule
        for name, episodes in ((schedule if isinstance(schedule, str) else "cover", loaded.episodes),
                               ("adaptive", adaptive.episodes)):
            table = budget_summary(episodes)
            table.insert(0, "schedule", name)
            table.insert(0, "run", label)
            rows.append(table)
    return pd.concat(rows, ignore_index=True)


def _records(frame: pd.DataFrame) -> list[dict]:
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()} for row in frame.to_dict("records")]


def reproduce_beyond(insertion_runs: str | Path, out: str | Path, push1d_run: str | Path | None = None,
                     workers: int = 1, progress=None) -> dict:
    """All three beyond-the-paper comparisons on the insertion reproduction's run directories.

    Args:
        insertion_runs: The ``runs/`` folder of ``probecommit reproduce insertion``
            (``B_cal_random``, ``B_test_random``, ``C_random``, ``C_random_corrected``,
            ``B_test_cover``, ``C_cover``).
        out: Results folder: ``results.json``, ``*.parquet`` and ``beyond.md``.
        push1d_run: A push1d run (random probes) for the continuous-loss adaptive comparison.
        workers: Local worker processes for the adaptive runs.
        progress: ``progress(step, done, total)``.

    Returns:
        The results dictionary written to ``results.json``.
    """
    import json

    runs, out = Path(insertion_runs), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    step = progress or (lambda *a: None)
    step("plateau: prefix vs hull", 0, 1)
    plateau = plateau_comparison(runs / "B_cal_random", runs / "B_test_random")
    step("move: jitter vs mh", 0, 1)
    moves = move_comparison({"B_test": runs / "B_test_random", "C": runs / "C_random",
                             "C_corrected": runs / "C_random_corrected"})
    step("adaptive probes", 0, 1)
    adaptive_runs = {"B_test": runs / "B_test_random", "C": runs / "C_random"}
    if push1d_run is not None:
        adaptive_runs["push1d"] = Path(push1d_run)
    adaptive = adaptive_comparison(adaptive_runs, out / "runs", workers=workers)
    cover = []
    for label, run in (("B_test", "B_test_cover"), ("C", "C_cover")):
        if (runs / run).is_dir():
            table = budget_summary(load_run(runs / run).episodes)
            table.insert(0, "schedule", "cover")
            table.insert(0, "run", label)
            cover.append(table)
    adaptive = pd.concat([adaptive, *cover], ignore_index=True)
    for name, frame in (("plateau", plateau), ("moves", moves), ("adaptive", adaptive)):
        write_with(out / f"{name}.parquet", frame.to_parquet)
    results = {"plateau": _records(plateau), "moves": _records(moves), "adaptive": _records(adaptive)}
    write_text(out / "results.json", json.dumps({"results": results}, indent=1, default=float))
    return results
