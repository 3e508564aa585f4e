"""An engine that returns NaN or raises on one query fails that episode, not the study."""

import pandas as pd
import yaml
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.report.tables import budget_summary
from probecommit.runner.study import run_study
from tests.runner.faults import inject, pick_faults

KEY = ["instance_id", "repeat", "k", "method"]


def _faulty_run(tmp_path, make_config, monkeypatch):
    cfg = make_config(repeats=4)
    clean = run_study(cfg, tmp_path / "clean")
    picked = pick_faults(clean.run_dir)
    inject(monkeypatch, **picked["faults"])
    return cfg, clean, picked, run_study(cfg, tmp_path / "faulty")


def test_faulty_engine_marks_episodes_failed_and_the_study_goes_on(tmp_path, make_config, monkeypatch):
    cfg, clean, picked, faulty = _faulty_run(tmp_path, make_config, monkeypatch)
    eps, ref = faulty.episodes, clean.episodes

    # NaN tap: every trajectory of that instance that taps there is one failed rollout row.
    rollout = eps[eps.method == "rollout"]
    assert rollout["instance_id"].eq(picked["nan_id"]).all()
    assert sorted(rollout["repeat"]) == picked["nan_repeats"]
    assert (rollout["status"] == "failed").all()
    assert rollout["error"].str.contains(rf"probe \d+: FloatingPointError: analytic returned \[nan\] for probe u={picked['nan_u']}").all()

    # Raising aim: exactly the commits at that aim on that instance fail, with the reason.
    commits = eps[eps.method != "rollout"]
    bad = commits["status"] == "failed"
    at_aim = (commits.instance_id == picked["raise_id"]) & (commits.action == picked["raise_aim"])
    assert bad.any() and (bad == at_aim).all()
    assert commits.loc[bad, "error"].eq("execute: RuntimeError: contact solver diverged").all()
    assert commits.loc[bad, "realized"].isna().all()

    # Everything else is exactly the clean run.
    lost = ref.set_index(["instance_id", "repeat"]).index.isin(
        [(picked["nan_id"], r) for r in picked["nan_repeats"]])
    expected = ref[~lost].reset_index(drop=True)
    got = commits.reset_index(drop=True)
    assert len(got) == len(expected)
    same = ["instance_id", "repeat", "k", "method", "action", "predicted", "z_true", "retained_lo",
            "retained_hi", "score_s", "post_var", "max_surprise", "n_retained"]
    pd.testing.assert_frame_equal(got[same], expected[same], check_exact=True, check_dtype=False)
    ok = ~bad.to_numpy()
    pd.testing.assert_frame_equal(got[ok].reset_index(drop=True),
                                  expected[ok].reset_index(drop=True).astype(got.dtypes.to_dict()),
                                  check_exact=True)

    # Counted in the manifest and the per-budget summary.
    n_commit_failed = int(bad.sum())
    assert faulty.manifest["failed_trajectories"] == len(picked["nan_repeats"])
    assert faulty.manifest["failed_rows"] == len(picked["nan_repeats"]) + n_commit_failed
    assert budget_summary(eps)["failed"].sum() == n_commit_failed
    assert faulty.failed_episodes == faulty.manifest["failed_rows"]


def test_cli_warns_with_the_failed_count(tmp_path, make_config, monkeypatch):
    cfg = make_config(repeats=4)
    clean = run_study(cfg, tmp_path / "clean")
    picked = pick_faults(clean.run_dir)
    inject(monkeypatch, **picked["faults"])
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg.model_dump(mode="json")))
    result = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "cli")])
    assert result.exit_code == 0, result.output
    n_failed = int((pd.read_parquet(tmp_path / "cli" / "episodes.parquet")["status"] != "ok").sum())
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1
    assert warnings[0].startswith(f"warning: {n_failed} of ")
    assert f"({len(picked['nan_repeats'])} trajectories lost in rollout)" in warnings[0]

    monkeypatch.undo()
    clean_cli = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "ok")])
    assert clean_cli.exit_code == 0 and "warning" not in clean_cli.stderr


def test_a_unit_whose_every_trajectory_fails_is_kept_and_counted(tmp_path, make_config, monkeypatch):
    cfg = make_config(unit_instances=1)
    clean = run_study(cfg, tmp_path / "clean")
    picked = pick_faults(clean.run_dir)
    inject(monkeypatch, **{**picked["faults"], "nan_u": None, "raise_x": float("nan")})
    faulty = run_study(cfg, tmp_path / "faulty")
    eps = faulty.episodes
    lost = eps["instance_id"] == picked["nan_id"]
    assert (eps.loc[lost, "method"] == "rollout").all() and lost.sum() == cfg.repeats
    assert faulty.manifest["failed_trajectories"] == cfg.repeats
    assert list(eps.columns) == list(clean.episodes.columns)  # the full schema, even so
    rest = eps[~lost].reset_index(drop=True)
    expected = clean.episodes[clean.episodes.instance_id != picked["nan_id"]].reset_index(drop=True)
    pd.testing.assert_frame_equal(rest, expected.astype(rest.dtypes.to_dict()), check_exact=True)
