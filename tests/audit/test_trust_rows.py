"""Trust the episode rows, by class (issue 38 items 2, 6, 8, 9, 18, 19).

One rule set for episode rows, on every path: derived columns are recomputed from the
intervals (a contradiction is said, and the recomputed value used), losses are of one
kind and in range, a run directory is read only whole and as its manifest lists it, and a
bootstrap never claims certainty from one cluster.
"""

from __future__ import annotations

import io
import json
import shutil

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probecommit.audit import audit
from probecommit.audit.io import EpisodeTableError, read_episodes, validate_episodes
from probecommit.audit.stats import cluster_bootstrap_mean
from tests.audit.test_io import ROBOT


def robot_frame() -> pd.DataFrame:
    return pd.read_csv(ROBOT)


def csv_of(frame: pd.DataFrame, tmp_path, name="log.csv"):
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


# ----------------------------------------------------------------------------- item 2: derived columns


def test_a_covered_column_that_contradicts_the_intervals_is_not_trusted(tmp_path):
    frame = robot_frame()
    truth = audit(csv_of(frame, tmp_path), resamples=100).table.set_index("k")
    frame["covered"] = True
    frame["escaped"] = False
    frame.loc[0, "z_true"] = 50.0  # outside the hull: escaped whatever the column says
    result = audit(csv_of(frame, tmp_path, "lie.csv"), resamples=100)
    got = result.table.set_index("k")
    assert got.loc[3, "coverage"] == pytest.approx(truth.loc[3, "coverage"])  # 1.000 before the fix
    assert got.loc[1, "escape"] == pytest.approx(1 / 6)
    assert any("'covered' contradicts the intervals" in n for n in result.notes)
    assert any("'escaped' contradicts the intervals" in n for n in result.notes)


# ----------------------------------------------------------------------------- item 8: impossible values


@pytest.mark.parametrize("column, value, message", [
    ("predicted", 5.0, "failure fraction in \\[0, 1\\]"),
    ("predicted", -3.0, "never negative"),
    ("realized", 2.0, "binary task's realized is 0 or 1"),
    ("realized", -1.0, "never negative"),
    ("predicted", 1e308, "beyond the magnitude"),
])
def test_impossible_losses_are_refused_naming_column_and_row(tmp_path, column, value, message):
    frame = robot_frame()
    frame.loc[2, column] = value
    with pytest.raises(EpisodeTableError, match=f"column '{column}' has .* at row 2 \\(CSV line 4\\).*{message}|"
                                                 f"column '{column}'.*row 2.*{message}"):
        read_episodes(csv_of(frame, tmp_path))


def test_a_realized_column_in_percent_is_refused(tmp_path):
    frame = robot_frame()
    frame["realized"] = frame["realized"] * 100
    with pytest.raises(EpisodeTableError, match="only 0 and 100, a failure in percent"):
        read_episodes(csv_of(frame, tmp_path))
    # Declared continuous (a miss in mm that happens to be 0 or 100), it is read.
    assert len(read_episodes(csv_of(frame, tmp_path), loss="continuous")) == len(frame)
    from typer.testing import CliRunner

    from probecommit.cli.app import app

    refused = CliRunner().invoke(app, ["audit", str(tmp_path / "log.csv"), "--resamples", "100"])
    assert refused.exit_code == 2 and "--loss continuous" in refused.output
    declared = CliRunner().invoke(app, ["audit", str(tmp_path / "log.csv"), "--resamples", "100", "--loss", "continuous"])
    assert declared.exit_code == 0, declared.output


def test_episode_row_applies_the_rules_when_a_row_is_made():
    from probecommit.audit.rows import episode_row

    good = dict(instance_id="p", k=1, z_true=0.0, action=0.0, predicted=0.2, realized=0.0, retained=(-1.0, 1.0),
                hull=(-2.0, 2.0))
    assert episode_row(**good)["covered"] is True
    for bad, message in (({"predicted": -0.1}, "cannot be negative"), ({"retained": (1.0, -1.0)}, "retained_lo"),
                         ({"hull": (float("nan"), 1.0)}, "hull_lo")):
        with pytest.raises(ValueError, match=message):
            episode_row(**{**good, **bad})


def test_continuous_misses_with_exact_zeros_are_read():
    frame = robot_frame()
    frame["realized"] = [0.0, 0.0, 0.0, 0.37, 0.0, 0.0, 1.25, 0.0, 0.0, 0.0, 0.0, 0.0]
    frame["predicted"] = 0.8
    assert len(validate_episodes(frame)) == len(frame)


# ----------------------------------------------------------------------------- item 9: few clusters


def test_one_cluster_gives_no_interval_and_a_warning(tmp_path):
    one = cluster_bootstrap_mean(np.array([0.0, 1.0, 1.0]), ["a", "a", "a"], resamples=200)
    assert one.estimate == pytest.approx(2 / 3) and np.isnan(one.lo) and np.isnan(one.hi)
    frame = robot_frame()
    frame["instance_id"] = "only"
    frame["repeat"] = frame.groupby("k").cumcount()
    result = audit(csv_of(frame, tmp_path), resamples=100)
    assert result.table["optimism_lo"].isna().all()
    assert any("1 cluster(s)" in n for n in result.notes)
    three = audit(ROBOT, resamples=100)
    assert any("only 3 clusters" in n and "unreliable" in n for n in three.notes)


# ----------------------------------------------------------------------------- items 6, 18, 19: run directories


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from probecommit.runner.study import run_study
    from tests.conftest import small_config

    return run_study(small_config(name="trust", instances={"count": 4}), tmp_path_factory.mktemp("r") / "run").run_dir


def copy_run(run_dir, tmp_path):
    target = tmp_path / "run"
    shutil.copytree(run_dir, target)
    return target


def test_a_run_without_config_and_shards_is_still_checked(tmp_path, run_dir):
    run = copy_run(run_dir, tmp_path)
    (run / "config.yaml").unlink()
    shutil.rmtree(run / "shards", ignore_errors=True)
    with pytest.raises(EpisodeTableError, match="config.yaml: listed in manifest.json but missing"):
        read_episodes(run)


@pytest.mark.parametrize("manifest, message", [
    ({"sha256": {}}, "field 'sha256' must map each file to its digest; it is empty"),
    ({"sha256": None}, "it is null"),
    ({"sha256": ["a"]}, "it is a JSON list"),
    ([1, 2], "must be a JSON object, got a JSON list"),
    ({"sha256": {"instances.parquet": "0" * 64}}, "episodes.parquet is read but not listed"),
])
def test_an_emptied_or_malformed_manifest_is_refused(tmp_path, run_dir, manifest, message):
    run = copy_run(run_dir, tmp_path)
    (run / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(EpisodeTableError, match=message):
        read_episodes(run)


def test_an_invalid_json_manifest_is_named(tmp_path, run_dir):
    from typer.testing import CliRunner

    from probecommit.cli.app import app

    run = copy_run(run_dir, tmp_path)
    (run / "manifest.json").write_text("{not json")
    result = CliRunner().invoke(app, ["audit", str(run), "--resamples", "100"])
    assert result.exit_code == 2 and "manifest.json: not valid JSON" in " ".join(result.output.split())
    assert "Traceback" not in result.output
    from probecommit.runner.replay import load_run
    from probecommit.store.rundir import RunDirError

    with pytest.raises(RunDirError, match="manifest.json: not valid JSON"):
        load_run(run)


def test_verify_names_a_malformed_manifest_and_results_file(tmp_path):
    from probecommit.report.verify import verify

    study = tmp_path / "results" / "x"
    study.mkdir(parents=True)
    (study / "MANIFEST.json").write_text(json.dumps({"sha256": None}))
    (study / "results.json").write_text("{oops")
    report = verify(tmp_path / "results")
    text = " ".join(report.failures)
    assert "MANIFEST.json: field 'sha256'" in text and "results.json: not valid JSON" in text


# ----------------------------------------------------------------------------- the property-based suite

CELLS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(["", "nan", "x", "1e308", "-0", "TRUE",
                                                                                   "100", "2", "1,5", "[red]"]),
                  st.integers(-5, 200))
COLUMNS = ["predicted", "realized", "z_true", "retained_lo", "retained_hi", "hull_lo", "hull_hi", "covered", "escaped"]


@given(edits=st.lists(st.tuples(st.integers(0, 11), st.sampled_from(COLUMNS), CELLS), min_size=1, max_size=4),
       parquet=st.booleans())
@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_edited_table_is_refused_in_one_line_or_audited_from_its_intervals(tmp_path_factory, edits, parquet):
    frame = robot_frame().assign(covered=True, escaped=False).astype(object)
    for row, column, value in edits:
        frame.loc[row, column] = value
    folder = tmp_path_factory.mktemp("t")
    if parquet:
        path = folder / "log.parquet"
        frame.astype(str).to_parquet(path)
    else:
        path = csv_of(frame, folder)
    try:
        df = read_episodes(path)
    except EpisodeTableError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)
        return
    ok = df[df["status"] == "ok"]
    z = ok["z_true"]
    assert (ok["covered"] == ((ok["retained_lo"] <= z) & (z <= ok["retained_hi"]))).all()
    assert (ok["escaped"] == ((z < ok["hull_lo"]) | (z > ok["hull_hi"]))).all()
    assert (ok["predicted"] >= 0).all() and (ok["realized"] >= 0).all()
    assert np.isfinite(ok[["predicted", "realized", "z_true"]].to_numpy(float)).all()
    if ok["realized"].isin([0.0, 1.0]).all():
        assert (ok["predicted"] <= 1).all()


JSON = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=False), st.text(max_size=8),
                              st.just("0" * 64), st.just("ab" * 32)),
                    lambda inner: st.one_of(st.lists(inner, max_size=3),
                                            st.dictionaries(st.sampled_from(["sha256", "episodes.parquet", "config.yaml",
                                                                             "../x", "/etc/passwd", "v"]), inner,
                                                            max_size=3)), max_leaves=10)


@given(content=st.one_of(JSON.map(json.dumps), st.text(max_size=20)))
@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_manifest_is_read_by_the_rules_or_refused_in_one_line(tmp_path_factory, content):
    from probecommit.store.manifest_rules import ManifestError, read_manifest

    path = tmp_path_factory.mktemp("m") / "manifest.json"
    path.write_text(content)
    try:
        data = read_manifest(path)
    except ManifestError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
        return
    assert isinstance(data, dict) and data["sha256"]
    for name, digest in data["sha256"].items():
        assert len(digest) == 64 and not name.startswith("/") and ".." not in name.split("/")
