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
