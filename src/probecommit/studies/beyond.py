"""Beyond the paper: the hull set at t = 1, the resample-move belief, adaptive probes.

Each comparison replays or recalibrates existing run directories (identical probes
for both arms where the probes do not depend on the belief), so the numbers in
``docs/beyond-the-paper.md`` come from this module and the frozen configs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import pandas as pd

from probecommit.runner.aside import in_own_process
from probecommit.runner.calibration import calibrate
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.store.safefile import write_text, write_with


#: The episode columns a publication stores of the moves' replays and the adaptive comparison's runs.
STORED_COLUMNS = ("instance_id", "repeat", "k", "method", "status", "predicted", "realized", "covered", "escaped",
                  "post_var")


def move_comparison(runs: Mapping[str, str | Path], budget: int = 8,
                    record: list[pd.DataFrame] | None = None) -> pd.DataFrame:
    """Escape, coverage, optimism and failure at ``budget`` under the paper's jitter and under MH.

    Args:
        runs: Label -> run directory (random probes; both arms replay the stored taps).
        budget: The probe budget compared.
        record: A list each replay's rows at ``budget`` are appended to (``run``, ``move``), for a
            publication to store and verify to compute the table again from (:func:`move_table`).

    Returns:
        One row per (run, move).
    """
    kept = []
    for label, path in runs.items():
        loaded = load_run(path)
        for move in ("jitter", "mh"):
            episodes, _ = replay_episodes(loaded, {"belief": {"move": move}})
            p = episodes[(episodes["method"] == "probe_robust") & (episodes["k"] == budget) & (episodes["status"] == "ok")]
            kept.append(p[[c for c in STORED_COLUMNS if c in p.columns]].assign(run=label, move=move))
    if record is not None:
        record.extend(kept)
    return move_table(pd.concat(kept, ignore_index=True))


def move_table(rows: pd.DataFrame) -> pd.DataFrame:
    """The moves table from each replay's ok probe-robust rows at the compared budget, in the order stored."""
    out = []
    for (label, move), p in rows.groupby(["run", "move"], sort=False):
        out.append({"run": label, "move": move, "n": len(p), "escape": p["escaped"].mean(),
                    "episode_coverage": p["covered"].mean(), "optimism": p["realized"].mean() - p["predicted"].mean(),
                    "failure": p["realized"].mean()})
    return pd.DataFrame(out)


def plateau_comparison(cal_run: str | Path, test_run: str | Path, resamples: int = 2000,
                       record: list[pd.DataFrame] | None = None) -> pd.DataFrame:
    """Calibrated cluster coverage and optimism per budget with the paper's prefix set and the hull set at t = 1.

    ``record``: a list each calibration's recorded rows (``runner.calibration.Recorder``, with ``plateau``)
    are appended to, for a publication to store and verify to recalibrate from."""
    parts = []
    for mode in ("prefix", "hull"):
        kept: list[pd.DataFrame] = []
        result = calibrate(cal_run, test_run, plateau=mode, resamples=resamples, record=kept)
        if record is not None:
            record.extend(part.assign(plateau=mode) for part in kept)
        parts.append(plateau_rows(result, mode))
    return pd.concat(parts, ignore_index=True)


def plateau_rows(result, mode: str) -> pd.DataFrame:
    """One plateau's rows of the table from its calibration result."""
    table = result.table3[["k", "threshold", "cluster_coverage_calibrated", "optimism_calibrated"]].copy()
    table.insert(0, "plateau", mode)
    return table


def probe_robust_by_budget(episodes: pd.DataFrame) -> pd.DataFrame:
    """Failure (or miss), coverage, escape, optimism and posterior variance per budget of the ok probe-robust
    rows: the adaptive comparison's numbers, which verify recomputes from the stored rows (not
    :func:`probecommit.report.tables.budget_summary`, which is per method and counts failed rows)."""
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


def adaptive_comparison(runs: Mapping[str, str | Path], out: str | Path, workers: int = 1,
                        record: list[pd.DataFrame] | None = None) -> pd.DataFrame:
    """Run each given run's config again with ``schedule: adaptive`` and compare per budget.

    Args:
        runs: Label -> a complete run directory with random or scheduled probes (its
            config, instances and seeds are reused; only the schedule changes).
        out: Folder for the adaptive runs (``<out>/<label>-adaptive``).
        workers: Local worker processes.
        record: A list each run's and schedule's ok probe-robust rows (:func:`summary_rows`, with
            ``run`` and ``schedule``) are appended to, for a publication to store.

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
            rows.append(summary_rows(episodes).assign(run=label, schedule=name))
    if record is not None:
        record.extend(rows)
    return adaptive_table(pd.concat(rows, ignore_index=True))


def summary_rows(episodes: pd.DataFrame) -> pd.DataFrame:
    """The rows :func:`probe_robust_by_budget` reads (ok probe-robust rows), what a publication stores per run and schedule."""
    p = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    return p[[c for c in STORED_COLUMNS if c in p.columns]].reset_index(drop=True)


def adaptive_table(rows: pd.DataFrame) -> pd.DataFrame:
    """The adaptive comparison's table from the stored rows of each run and schedule, in the order stored."""
    parts = []
    for (label, name), part in rows.groupby(["run", "schedule"], sort=False):
        table = probe_robust_by_budget(part)
        table.insert(0, "schedule", name)
        table.insert(0, "run", label)
        parts.append(table)
    return pd.concat(parts, ignore_index=True)


#: The rows verify recomputes beyond's three tables from (``part``: plateau, moves, adaptive).
EPISODES_FILE = "beyond_episodes.parquet"
PLATEAU_RESAMPLES = 2000


def _records(frame: pd.DataFrame) -> list[dict]:
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()} for row in frame.to_dict("records")]


def _plateau_part(cal_run: Path, test_run: Path) -> tuple[pd.DataFrame, list[pd.DataFrame]]:
    commits: list[pd.DataFrame] = []
    return plateau_comparison(cal_run, test_run, resamples=PLATEAU_RESAMPLES, record=commits), commits


def _moves_part(runs: dict[str, Path]) -> tuple[pd.DataFrame, list[pd.DataFrame]]:
    moved: list[pd.DataFrame] = []
    return move_comparison(runs, record=moved), moved


def _adaptive_part(runs: Path, adaptive_runs: dict[str, Path], out: Path, workers: int) -> pd.DataFrame:
    """The adaptive comparison's stored rows: each run and schedule's, then the cover runs' (``reproduce_beyond``)."""
    kept_rows: list[pd.DataFrame] = []
    adaptive_comparison(adaptive_runs, out, workers=workers, record=kept_rows)
    for label, run in (("B_test", "B_test_cover"), ("C", "C_cover")):
        if (runs / run).is_dir():
            kept_rows.append(summary_rows(load_run(runs / run).episodes).assign(run=label, schedule="cover"))
    return pd.concat(kept_rows, ignore_index=True)


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
    # Each comparison in a process of its own (``runner.aside``): what one holds (a calibration's beliefs, a whole
    # run's replays, the adaptive units' scores) leaves with it, so none sets the target's peak on top of another's.
    step("plateau: prefix vs hull", 0, 1)
    plateau, commits = in_own_process(_plateau_part, runs / "B_cal_random", runs / "B_test_random")
    step("move: jitter vs mh", 0, 1)
    moves, moved = in_own_process(_moves_part, {"B_test": runs / "B_test_random", "C": runs / "C_random",
                                                "C_corrected": runs / "C_random_corrected"})
    step("adaptive probes", 0, 1)
    adaptive_runs = {"B_test": runs / "B_test_random", "C": runs / "C_random"}
    if push1d_run is not None:
        adaptive_runs["push1d"] = Path(push1d_run)
    stored = in_own_process(_adaptive_part, runs, adaptive_runs, out / "runs", workers)
    adaptive = adaptive_table(stored)
    for name, frame in (("plateau", plateau), ("moves", moves), ("adaptive", adaptive)):
        write_with(out / f"{name}.parquet", frame.to_parquet)
    kept = pd.concat([pd.concat(commits, ignore_index=True).assign(part="plateau"),
                      pd.concat(moved, ignore_index=True).assign(part="moves"), stored.assign(part="adaptive")],
                     ignore_index=True)
    write_with(out / EPISODES_FILE, lambda buf: kept.to_parquet(buf, compression="zstd", index=False))
    results = {"plateau": _records(plateau), "moves": _records(moves), "adaptive": _records(adaptive),
               "settings": {"plateau_resamples": PLATEAU_RESAMPLES}}
    write_text(out / "results.json", json.dumps({"results": results}, indent=1, default=float))
    return results
