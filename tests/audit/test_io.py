"""read_episodes: a real robot's CSV log, run directories, and clear errors on malformed input."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.audit.io import EpisodeTableError, read_episodes, validate_episodes
from probecommit.audit.metrics import audit_table
from probecommit.audit.synthetic import synthetic_episodes

DATA = Path(__file__).parent / "data"
ROBOT = DATA / "robot_log.csv"


def _write(tmp_path, text: str, name: str = "log.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _robot_lines() -> list[str]:
    return ROBOT.read_text().splitlines()


def test_robot_log_gives_hand_computed_audit_numbers():
    df = read_episodes(ROBOT)
    assert df.attrs["n_total"] == 12 and df.attrs["n_failed"] == 1
    # covered/escaped were absent and are derived from the intervals (closed intervals).
    assert df["covered"].tolist()[:8] == [True, False, True, False, True, True, True, True]
    a = audit_table(df, resamples=300, seed=1).set_index("k")
    k1, k3 = a.loc[1], a.loc[3]
    # k = 1: six ok episodes.
    assert k1["n_episodes"] == 6 and k1["n_failed"] == 0 and k1["n_instances"] == 3
    assert k1["coverage"] == pytest.approx(4 / 6)
    assert k1["cluster_coverage"] == pytest.approx(1 / 3)
    assert k1["escape"] == pytest.approx(0.0)
    assert k1["realized"] == pytest.approx(0.5)
    assert k1["predicted"] == pytest.approx(1.7 / 6)
    assert k1["optimism"] == pytest.approx(0.5 - 1.7 / 6)
    # k = 3: the failed episode is excluded and counted.
    assert k3["n_episodes"] == 5 and k3["n_failed"] == 1
    assert k3["coverage"] == pytest.approx(0.6)
    assert k3["cluster_coverage"] == pytest.approx(1 / 3)
    assert k3["escape"] == pytest.approx(0.4)
    assert k3["realized"] == pytest.approx(0.4)
    assert k3["predicted"] == pytest.approx(0.08)
    assert k3["optimism"] == pytest.approx(0.32)
    for m in ("coverage", "cluster_coverage", "escape", "optimism"):
        assert (a[f"{m}_lo"] <= a[m] + 1e-12).all() and (a[m] <= a[f"{m}_hi"] + 1e-12).all()


def test_missing_column_is_named(tmp_path):
    lines = _robot_lines()
    header = lines[0].split(",")
    drop = header.index("z_true")
    text = "\n".join(",".join(c for i, c in enumerate(line.split(",")) if i != drop) for line in lines)
    with pytest.raises(EpisodeTableError, match=r"missing required column\(s\) z_true"):
        read_episodes(_write(tmp_path, text))


def test_nan_outcome_names_column_and_first_row(tmp_path):
    lines = _robot_lines()
    parts = lines[3].split(",")  # data row 2
    parts[5] = "nan"
    lines[3] = ",".join(parts)
    with pytest.raises(EpisodeTableError, match=r"column 'realized' has NaN at row 2 \(CSV line 4\)"):
        read_episodes(_write(tmp_path, "\n".join(lines)))


def test_nan_outcome_on_failed_row_is_allowed():
    df = read_episodes(ROBOT)
    assert np.isnan(df.loc[11, "realized"]) and df.loc[11, "status"] == "failed"


@pytest.mark.parametrize("column,value", [("predicted", "high"), ("z_true", "-9.8mm"), ("realized", "fail")])
def test_non_numeric_text_names_column(tmp_path, column, value):
    lines = _robot_lines()
    col = lines[0].split(",").index(column)
    parts = lines[5].split(",")
    parts[col] = value
    lines[5] = ",".join(parts)
    with pytest.raises(EpisodeTableError, match=rf"column '{column}' must be numeric.*'{value}' at row 4"):
        read_episodes(_write(tmp_path, "\n".join(lines)))


def test_repeats_of_unequal_count_are_refused(tmp_path):
    lines = [ln for ln in _robot_lines() if not ln.startswith("pos_0.0,1,1,")]
    with pytest.raises(EpisodeTableError, match=r"repeats of unequal count at method='probe_robust', k=1.*'pos_0.0' has 1"):
        read_episodes(_write(tmp_path, "\n".join(lines)))


def test_retained_lo_above_hi_is_refused(tmp_path):
    lines = _robot_lines()
    lines[1] = lines[1].replace("-12.0,-8.0,", "-8.0,-12.0,")
    with pytest.raises(EpisodeTableError, match=r"retained_lo > retained_hi at row 0"):
        read_episodes(_write(tmp_path, "\n".join(lines)))


def test_bad_status_duplicate_episode_and_fractional_repeat(tmp_path):
    lines = _robot_lines()
    bad = lines[:2] + [lines[2].replace(",ok", ",maybe")] + lines[3:]
    with pytest.raises(EpisodeTableError, match="column 'status' must be 'ok' or 'failed'"):
        read_episodes(_write(tmp_path, "\n".join(bad)))
    dup = lines + [lines[1]]
    with pytest.raises(EpisodeTableError, match="duplicate episode"):
        read_episodes(_write(tmp_path, "\n".join(dup)))
    frac = lines[:1] + [lines[1].replace("pos_m9.8,0,1,", "pos_m9.8,0.5,1,")] + lines[2:]
    with pytest.raises(EpisodeTableError, match="column 'repeat' must be an integer"):
        read_episodes(_write(tmp_path, "\n".join(frac)))


def test_unknown_format_missing_file_and_empty_table(tmp_path):
    with pytest.raises(EpisodeTableError, match="no episode table"):
        read_episodes(tmp_path / "nothing.csv")
    with pytest.raises(EpisodeTableError, match="has no episodes.parquet"):
        read_episodes(tmp_path)
    with pytest.raises(EpisodeTableError, match="unsupported"):
        read_episodes(_write(tmp_path, "x", "log.xlsx"))
    with pytest.raises(EpisodeTableError, match="no rows"):
        read_episodes(_write(tmp_path, _robot_lines()[0]))


def test_given_indicators_are_parsed_but_recomputed(tmp_path):
    lines = _robot_lines()
    out = [lines[0] + ",covered"] + [ln + (",TRUE" if i % 2 else ",0") for i, ln in enumerate(lines[1:])]
    df = read_episodes(_write(tmp_path, "\n".join(out)))
    # Derived columns are never trusted: the intervals' values are used and the contradiction said.
    assert df["covered"].tolist()[:8] == [True, False, True, False, True, True, True, True]
    assert any("contradicts the intervals" in n for n in df.attrs["notes"])
    assert df["escaped"].dtype == bool


def test_run_directory_and_parquet_roundtrip(tmp_path):
    table = synthetic_episodes(6, 2, (1, 2), n_particles=64, seed=3)
    run = tmp_path / "run"
    run.mkdir()
    table.to_parquet(run / "episodes.parquet")
    from_dir = read_episodes(run)
    from_file = read_episodes(run / "episodes.parquet")
    pd.testing.assert_frame_equal(from_dir, from_file)
    pd.testing.assert_frame_equal(from_dir[table.columns], table, check_dtype=False)


def test_integer_instance_ids_and_in_memory_validation():
    df = read_episodes(ROBOT)
    df["instance_id"] = df["instance_id"].map({"pos_m9.8": 1.0, "pos_0.0": 2.0, "pos_7.5": 3.0})
    out = validate_episodes(df.drop(columns=["covered", "escaped"]))
    assert sorted(out["instance_id"].unique()) == ["1", "2", "3"]


def test_rollout_failures_count_as_present_repeats():
    """Our runner records a trajectory whose probing failed as one 'rollout' row."""
    table = synthetic_episodes(4, 2, (1, 2), n_particles=32, seed=0)
    gone = (table["instance_id"] == table["instance_id"].iloc[0]) & (table["repeat"] == 1)
    rollout = pd.DataFrame({"instance_id": [table["instance_id"].iloc[0]], "repeat": [1], "k": [0],
                            "method": ["rollout"], "variant": ["deployed"], "status": ["failed"],
                            "error": ["probe 1: engine NaN"]})
    df = validate_episodes(pd.concat([table.loc[~gone], rollout], ignore_index=True))
    a = audit_table(df, resamples=100)
    assert set(a["method"]) == {"probe_robust"}
    assert (a["n_failed"] == 1).all() and (a["n_episodes"] == 7).all()


def test_interval_wider_than_hull_is_counted_duplicate_header_and_missing_budget_are_refused(tmp_path):
    table = synthetic_episodes(6, 2, (1, 2), n_particles=64, seed=3)
    wide = table.copy()
    wide.loc[0, "retained_lo"] = wide.loc[0, "hull_lo"] - 1.0
    notes = validate_episodes(wide).attrs["notes"]
    assert notes and "1 row(s) have a retained interval wider than the particle hull" in notes[0]
    path = tmp_path / "dup.csv"
    text = table.to_csv(index=False)
    header, rest = text.split("\n", 1)
    path.write_text(header + ",predicted\n" + "\n".join(line + ",0.5" for line in rest.strip().split("\n")) + "\n")
    with pytest.raises(EpisodeTableError, match="'predicted' appears more than once"):
        read_episodes(path)
    first = table["instance_id"].iloc[0]
    missing = table[~((table["instance_id"] == first) & (table["k"] == 2))]
    with pytest.raises(EpisodeTableError, match=rf"instance '{first}' has no rows at budget\(s\) \[2\]"):
        validate_episodes(missing)


def test_nullable_boolean_na_is_derived_like_an_empty_csv_cell_and_optional_text_is_ignored():
    table = synthetic_episodes(6, 2, (1, 2), n_particles=64, seed=3)
    na = table.copy()
    na["covered"] = pd.array([True] * (len(na) - 1) + [None], dtype="boolean")
    derived = validate_episodes(na)
    z, lo, hi = derived["z_true"], derived["retained_lo"], derived["retained_hi"]
    assert (derived["covered"] == ((lo <= z) & (z <= hi))).all()
    text = table.copy()
    text["post_var"] = "not a number"
    out = validate_episodes(text)
    assert "post_var" not in out.columns and any("optional column 'post_var' ignored" in n for n in out.attrs["notes"])


@given(st.lists(st.sampled_from(["instance_id", "repeat", "k", "predicted", "realized", "z_true", "retained_lo",
                                  "retained_hi", "hull_lo", "hull_hi"]), min_size=1, max_size=3))
@settings(max_examples=25, deadline=None)
def test_generated_duplicate_headers_are_refused(duplicates):
    import io

    table = synthetic_episodes(4, 2, (1,), n_particles=32, seed=1)
    text = table.to_csv(index=False)
    header, rest = text.split("\n", 1)
    extra = "".join("," + d for d in duplicates)
    body = "\n".join(line + ",1" * len(duplicates) for line in rest.strip().split("\n"))
    frame = pd.read_csv(io.StringIO(header + extra + "\n" + body), dtype=str, keep_default_na=False)
    with pytest.raises(EpisodeTableError, match="appears more than once"):
        validate_episodes(frame)


@given(st.floats(0.01, 5.0), st.integers(0, 7))
@settings(max_examples=25, deadline=None)
def test_generated_inverted_intervals_are_refused(gap, row):
    table = synthetic_episodes(4, 2, (1,), n_particles=32, seed=2)
    bad = table.copy()
    bad.loc[row, "retained_hi"] = bad.loc[row, "retained_lo"] - gap
    with pytest.raises(EpisodeTableError, match="retained_lo > retained_hi"):
        validate_episodes(bad)


def _spoiled(table: pd.DataFrame, how: str, row: int) -> pd.DataFrame:
    """A copy of an episode table with one value of ``row`` made wrong in the way ``how`` names."""
    bad = table.copy()
    column, value = {"nan": ("predicted", np.nan), "inf": ("z_true", np.inf), "huge": ("hull_hi", 1e300),
                     "negative": ("realized", -1.0), "inverted": ("hull_lo", bad.loc[row, "hull_hi"] + 1.0),
                     "status": ("status", "lost"), "not binary": ("realized", 2.0)}[how]
    bad.loc[row, column] = value
    return bad


@pytest.mark.parametrize("how", ["nan", "inf", "huge", "negative", "inverted", "status", "not binary", "none"])
@pytest.mark.parametrize("row", [0, 5])
def test_a_built_tables_values_are_refused_as_validate_episodes_refuses_them(how, row):
    """``check_episode_values`` (a calibration's check of the tables its commits build) raises the
    same error as ``validate_episodes`` on each wrong value of a table in the schema's types, and
    nothing on a good table."""
    from probecommit.audit.io import check_episode_values

    table = synthetic_episodes(4, 2, (1, 2), n_particles=32, seed=3).assign(status="ok")
    table.loc[7, ["status", "predicted", "realized"]] = ["failed", np.nan, np.nan]  # a failed row's NaN is allowed
    bad = table if how == "none" else _spoiled(table, how, row)
    try:
        validate_episodes(bad, "t", structure=False)
    except EpisodeTableError as exc:
        with pytest.raises(EpisodeTableError) as mine:
            check_episode_values(bad, "t")
        assert str(mine.value) == str(exc)
    else:
        assert how == "none"
        check_episode_values(bad, "t")
