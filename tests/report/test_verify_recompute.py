"""verify's recomputations of the studies the quick tamper publication does not hold (GRU, engine scans,
beyond's moves and adaptive tables): a stored table gives the published numbers, an edited cell does not."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd

from probecommit.report.verify import Report, check_recomputed


def _gru_folder(tmp_path):
    from probecommit.studies.gru import summarize_gru

    rng = np.random.default_rng(3)
    ids = np.repeat([f"i{n}" for n in range(6)], 3)
    rows = pd.DataFrame({"instance_id": ids, "repeat": np.tile([0, 1, 2], 6), "k": 5,
                         "realized": rng.uniform(0, 0.2, 18), **{f"gru_seed_{s}": rng.uniform(0, 0.2, 18) for s in range(3)}})
    folder = tmp_path / "gru"
    folder.mkdir()
    rows.to_parquet(folder / "gru_episodes.parquet")
    bootstrap = {"resamples": 300, "seed": 11}
    results = {**summarize_gru(rows, bootstrap, 0.02), "training_loss_last_mean": 0.1, "bootstrap": bootstrap}
    return folder, json.loads(json.dumps(results)), rows


def test_the_gru_table_is_recomputed_from_its_episodes(tmp_path):
    folder, results, rows = _gru_folder(tmp_path)
    assert results["seeds"] == 3 and results["episodes"] == 18
    assert math.isclose(results["gru_miss"], float(rows[[f"gru_seed_{s}" for s in range(3)]].to_numpy().mean()))
    report = Report()
    keys = check_recomputed(folder, results, report)
    assert report.ok, report.failures
    assert {"gru_miss", "gru_minus_pipeline", "seed_miss_sd", "equivalent"} <= keys
    assert "training_loss_last_mean" not in keys  # it needs the training run: traced only


def test_an_edited_gru_episode_fails_naming_file_and_number(tmp_path):
    folder, results, rows = _gru_folder(tmp_path)
    rows.loc[4, "gru_seed_1"] += 0.5
    rows.to_parquet(folder / "gru_episodes.parquet")
    report = Report()
    check_recomputed(folder, results, report)
    assert any("gru_episodes.parquet" in f and str(results["gru_miss"]) in f for f in report.failures), report.failures


def test_engine_scan_summaries_by_hand():
    from probecommit.studies.engines import scan_summaries

    rows = pd.DataFrame({"engine": "e", "kind": ["boundary", "boundary", "capture", "capture", "capture_side"],
                         "offset": [0.9, 1.1, np.nan, np.nan, np.nan], "ratio": [np.nan, np.nan, 1.0, 1.2, np.nan],
                         "enters_beyond": [np.nan, np.nan, np.nan, np.nan, 1.0]})
    got = scan_summaries(rows)["e"]
    assert math.isclose(got["boundary"]["delta"], 1.0) and math.isclose(got["boundary"]["sd"], math.sqrt(0.02))
    assert got["boundary"]["scans"] == 2 and math.isclose(got["boundary"]["shift_vs_deployed_mm"], 2.2)
    assert math.isclose(got["capture"]["ratio_mean"], 1.1) and got["capture"]["truths"] == 2
    assert got["capture"]["sides_entering_beyond"] == 1


def test_beyond_moves_and_adaptive_tables_by_hand():
    from probecommit.studies.beyond import adaptive_table, move_table

    rows = pd.DataFrame({"run": "B", "move": ["jitter", "jitter", "mh"], "k": 8, "method": "probe_robust",
                         "status": "ok", "realized": [1.0, 0.0, 1.0], "predicted": [0.5, 0.25, 0.5],
                         "covered": [True, False, True], "escaped": [False, True, False], "post_var": [1.0, 3.0, 2.0]})
    moves = move_table(rows).set_index("move")
    assert moves.loc["jitter", "n"] == 2 and moves.loc["jitter", "failure"] == 0.5
    assert moves.loc["jitter", "optimism"] == 0.5 - 0.375 and moves.loc["mh", "escape"] == 0.0
    adaptive = adaptive_table(rows.rename(columns={"move": "schedule"}))
    assert list(adaptive["schedule"]) == ["jitter", "mh"] and list(adaptive["post_var"]) == [2.0, 2.0]


def test_scan_rows_give_the_scans_own_summaries():
    from probecommit.studies.engines import CaptureResult, scan_rows, scan_summaries
    from probecommit.studies.scan import ScanResult

    boundary = ScanResult(pd.DataFrame({"instance_id": ["a", "a", "b"], "side": [-1, 1, 1], "offset": [0.91, 0.93, 0.9]}),
                          pd.DataFrame())
    capture = CaptureResult(pd.DataFrame({"instance_id": ["a", "a"], "side": [-1, 1], "half_width": [2.0, 2.1],
                                          "enters_beyond": [False, True]}),
                            pd.DataFrame({"instance_id": ["a"], "window": [2.05], "ratio": [1.01]}))
    rows = pd.concat([scan_rows("x", boundary, capture), scan_rows("y", boundary, capture)], ignore_index=True)
    rows = pd.read_parquet(_roundtrip(rows))
    got = scan_summaries(rows)
    assert list(got) == ["x", "y"]
    assert got["x"] == {"boundary": boundary.summary(), "capture": capture.summary()}


def _roundtrip(frame: pd.DataFrame):
    import io

    buf = io.BytesIO()
    frame.to_parquet(buf, compression="zstd", index=False)
    buf.seek(0)
    return buf


def test_beyond_comparisons_recompute_from_their_records(tmp_path):
    """The moves and the plateau comparison on two small runs: their tables again from the stored rows."""
    from probecommit.runner.calibration import calibration_from_tables
    from probecommit.runner.replay import load_run
    from probecommit.runner.study import run_study
    from probecommit.studies.beyond import move_comparison, move_table, plateau_comparison, plateau_rows
    from tests.conftest import small_config

    paths = {}
    for split, seed in (("cal", 3), ("test", 4)):
        cfg = small_config(name=split, instances={"split": split, "count": 6, "seed": seed},
                           methods=["blind_robust", "probe_robust"])
        paths[split] = run_study(cfg, tmp_path / split).run_dir
    moved: list = []
    moves = move_comparison({"T": paths["test"]}, budget=5, record=moved)
    pd.testing.assert_frame_equal(move_table(pd.read_parquet(_roundtrip(pd.concat(moved, ignore_index=True)))), moves)
    commits: list = []
    plateau = plateau_comparison(paths["cal"], paths["test"], resamples=100, record=commits)
    stored = pd.read_parquet(_roundtrip(pd.concat(commits, ignore_index=True)))
    episodes = {n: load_run(p).episodes for n, p in paths.items()}
    again = []
    for mode, part in stored.groupby("plateau", sort=False):
        budgets = sorted(int(k) for k in part.loc[part.request == "set_margin", "k"].unique())
        again.append(plateau_rows(calibration_from_tables(part.reset_index(drop=True), episodes["cal"], episodes["test"],
                                                          0.2, budgets, resamples=100), mode))
    pd.testing.assert_frame_equal(pd.concat(again, ignore_index=True), plateau)


def test_fig_1b_is_drawn_again_from_its_series(tmp_path):
    """Fig. 1b from a stored series: drawn again, the same bytes; a particle moved in the series, not."""
    from probecommit.report.figures import draw_belief_snapshots
    from probecommit.report.verify import check_figures

    rng = np.random.default_rng(2)
    beliefs = [pd.DataFrame({"part": "belief", "k": k, "z": rng.normal(0, 3.0 / k, 64), "weight": np.full(64, 1 / 64)})
               for k in (1, 3)]
    rest = pd.DataFrame({"part": ["aim", "aim", "tap", "tap", "tap"], "k": [1, 3, 1, 2, 3],
                         "z": [0.5, 0.1, -3.0, 3.0, 0.0], "weight": [0.0, 1.0, 0.0, 0.0, -15.0]})
    series = pd.concat([*beliefs, rest], ignore_index=True).assign(z_true=0.2, low=-10.0, high=10.0)
    folder = tmp_path / "setup"
    folder.mkdir()
    series.to_parquet(folder / "fig_1b_data.parquet")
    draw_belief_snapshots(series, folder / "fig_1b_overview_belief.png")
    report = Report()
    check_figures(folder, report)
    assert report.ok and report.counts["recomputed"] == 2, (report.counts, report.failures)
    series.loc[3, "z"] += 4.0
    series.to_parquet(folder / "fig_1b_data.parquet")
    report = Report()
    check_figures(folder, report)
    assert any("fig_1b_overview_belief" in f and "drawn again" in f for f in report.failures), report.failures
