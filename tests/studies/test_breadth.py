"""Breadth study (Table II rows): hand-made tables with known answers, the figure, quick runs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.breadth import (
    as_success,
    truth_sign_flip,
    breadth_markdown,
    breadth_row,
    breadth_table,
    budget_curve,
    plot_budget_curves,
    run_breadth,
)


def table(values: dict[tuple[str, int], list[list[float]]]) -> pd.DataFrame:
    """Episodes from ``{(method, k): miss[instance][repeat]}``."""
    rows = []
    for (method, k), grid in values.items():
        for i, reps in enumerate(grid):
            for r, v in enumerate(reps):
                rows.append({"instance_id": f"i{i}", "repeat": r, "k": k, "method": method, "realized": v, "status": "ok"})
    return pd.DataFrame(rows)


def test_row_means_and_paired_reduction_known_answer():
    ep = table({
        ("blind_bayes", 0): [[0.9, 0.9], [0.9, 0.9], [0.9, 0.9]],
        ("blind_robust", 0): [[1.0, 0.8], [0.6, 0.6], [0.9, 0.3]],
        ("probe_robust", 2): [[0.5, 0.5], [0.5, 0.5], [0.5, 0.5]],
        ("probe_robust", 5): [[0.2, 0.4], [0.5, 0.3], [0.1, 0.1]],
    })
    row = breadth_row(ep, "toy", k=5, resamples=500)
    assert row["blind_bayes"] == pytest.approx(0.9)
    assert row["blind_robust"] == pytest.approx(0.7)
    assert row["probe_robust"] == pytest.approx(1.6 / 6)
    # The paper's Delta, Blind-Bayes - Probe-Robust: per-instance reductions 0.6, 0.5, 0.8.
    assert row["paired"] == pytest.approx(1.9 / 3)
    assert row["n_pairs"] == 6 and row["n_instances"] == 3
    assert 0.5 - 1e-12 <= row["paired_lo"] <= row["paired"] <= row["paired_hi"] <= 0.8 + 1e-12
    # The extra column, Blind-Robust - Probe-Robust: per-instance reductions 0.6, 0.2, 0.5.
    assert row["paired_robust"] == pytest.approx(1.3 / 3)
    assert 0.2 - 1e-12 <= row["paired_robust_lo"] <= row["paired_robust_hi"] <= 0.6 + 1e-12
    assert row["blind_bayes_lo"] == pytest.approx(0.9) and row["blind_bayes_hi"] == pytest.approx(0.9)
    k2 = breadth_row(ep, "toy", k=2, resamples=200)
    assert (k2["paired"], k2["paired_robust"]) == pytest.approx((0.4, 0.2))


def test_constant_reduction_has_a_degenerate_interval_and_failed_rows_are_ignored():
    ep = table({("blind_robust", 0): [[1.0, 1.0]] * 4, ("probe_robust", 5): [[0.4, 0.4]] * 4})
    ep = pd.concat([ep, pd.DataFrame([{"instance_id": "i0", "repeat": 9, "k": 0, "method": "rollout",
                                       "realized": np.nan, "status": "failed"}])], ignore_index=True)
    row = breadth_row(ep, "flat", resamples=200)
    assert (row["paired_robust"], row["paired_robust_lo"], row["paired_robust_hi"]) == pytest.approx((0.6, 0.6, 0.6))
    assert np.isnan(row["blind_bayes"]) and np.isnan(row["paired"])  # no Blind-Bayes rows: missing, not zero


def test_budget_curve_table_markdown_and_figure(tmp_path):
    ep = table({("blind_bayes", 0): [[0.5, 0.5]], ("blind_robust", 0): [[0.6, 0.6]],
                ("probe_robust", 2): [[0.3, 0.3]], ("probe_robust", 5): [[0.1, 0.1]]})
    curve = budget_curve(ep, "toy", resamples=100)
    assert list(zip(curve["method"], curve["k"])) == [("blind_bayes", 0), ("blind_robust", 0), ("probe_robust", 2), ("probe_robust", 5)]
    assert curve["mean"].tolist() == pytest.approx([0.5, 0.6, 0.3, 0.1])
    tab = breadth_table({"push2d": ep}, resamples=100)
    md = breadth_markdown(tab)
    # One instance is one cluster: no bootstrap interval (issue 38: never a zero-width one).
    assert "push2d (ours, k=5) | m | 0.500 | 0.600 | 0.100 | 0.400 [nan, nan] | 0.500 [nan, nan] |" in md
    assert "push2d (paper, k=5) | m | 0.252 | 0.307 | 0.221 | 0.031 [0.007, 0.054] | -- |" in md
    # Shuffleboard's cells are mean / P90 and its column is Probe-Robust(2).
    md = breadth_markdown(breadth_table({"shuffleboard": ep}, resamples=100))
    assert "shuffleboard (ours, k=2) | m (mean / P90) | 0.500 / 0.500 | 0.600 / 0.600 | 0.300 / 0.300 |" in md
    paths = plot_budget_curves(pd.concat([curve, budget_curve(ep, "other", resamples=100)]), tmp_path / "curves")
    assert [p.suffix for p in paths] == [".png", ".pdf"] and all(p.stat().st_size > 0 for p in paths)


def test_run_breadth_quick_push1d(tmp_path):
    out = run_breadth(["push1d"], tmp_path, quick=True, resamples=100)
    row = out.iloc[0]
    assert row["family"] == "push1d" and row["n_instances"] == 2 and row["n_pairs"] == 4
    assert np.isfinite([row["blind_bayes"], row["blind_robust"], row["probe_robust"], row["paired"]]).all()
    # Resumes the finished run: same table.
    again = run_breadth(["push1d"], tmp_path, quick=True, resamples=100)
    pd.testing.assert_frame_equal(out, again)


def test_run_breadth_runs_each_family_in_a_process_of_its_own_with_the_same_table(tmp_path):
    """The family's run moves to a process of its own for its memory (issue 42); its table is the in-place run's."""
    from probecommit.runner.study import run_study
    from probecommit.studies.breadth import paper_config, quick_config

    out = run_breadth(["push1d"], tmp_path / "aside", quick=True, resamples=100)
    episodes = run_study(quick_config(paper_config("push1d")), tmp_path / "here" / "push1d").episodes
    pd.testing.assert_frame_equal(out, breadth_table({"push1d": episodes}, 5, resamples=100, seed=0), check_exact=True)


@pytest.mark.mujoco
def test_run_breadth_quick_mujoco_families(tmp_path):
    pytest.importorskip("mujoco")
    out = run_breadth(["push2d", "darts"], tmp_path, quick=True, resamples=100)
    assert out["family"].tolist() == ["push2d", "darts"]
    assert np.isfinite(out[["blind_bayes", "blind_robust", "probe_robust", "paired"]].to_numpy(float)).all()


def test_success_rows_swap_their_intervals():
    row = {"family": "grasp", "blind_bayes": 0.7, "blind_bayes_lo": 0.6, "blind_bayes_hi": 0.8,
           "blind_robust": 0.5, "blind_robust_lo": 0.4, "blind_robust_hi": 0.6,
           "probe_robust": 0.2, "probe_robust_lo": 0.1, "probe_robust_hi": 0.3, "paired": 0.3}
    out = as_success(row)
    assert (out["blind_bayes"], out["blind_bayes_lo"], out["blind_bayes_hi"]) == pytest.approx((0.3, 0.2, 0.4))
    assert out["paired"] == 0.3 and out["metric"] == "success"


def test_truth_sign_flip_against_hand_enumeration():
    # Three truths improve, three tie: the exact p over the three untied signs is 2 / 8 = 0.25.
    rows = []
    for t, (bb, pr) in enumerate([(0, 1), (0, 1), (1, 0.5), (1, 1), (0, 0), (0.5, 0.5)]):
        for r in range(2):
            rows.append({"instance_id": f"t{t}", "repeat": r, "k": 0, "method": "blind_bayes", "realized": 1 - bb})
            rows.append({"instance_id": f"t{t}", "repeat": r, "k": 8, "method": "probe_robust", "realized": 1 - pr})
    res = truth_sign_flip(pd.DataFrame(rows), {f"t{t}": f"t{t}" for t in range(6)}, 8)
    assert (res["n_improve"], res["n_tie"], res["n_worse"]) == (2, 3, 1)
    assert res["p_sign_flip"] == pytest.approx(0.5)  # |1 + 1 - 0.5| = 1.5: reached by 4 of the 8 sign patterns
    rows = [r for r in rows if r["instance_id"] != "t2"] + [
        {"instance_id": "t2", "repeat": r, "k": k, "method": m, "realized": v}
        for r in range(2) for k, m, v in ((0, "blind_bayes", 1.0), (8, "probe_robust", 0.5))]
    res = truth_sign_flip(pd.DataFrame(rows), {f"t{t}": f"t{t}" for t in range(6)}, 8)
    assert (res["n_improve"], res["n_tie"]) == (3, 3) and res["p_sign_flip"] == pytest.approx(0.25)
