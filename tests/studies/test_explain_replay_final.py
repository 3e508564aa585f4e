"""``replay_final.replay_at``: a replay committed at one budget only gives the full replay's rows at that
budget, bit for bit (the explain steps that read the final budget alone use it, issue 42)."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.errors import UsageError
from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.runner.study import run_study
from probecommit.studies.explain.replay_final import replay_at
from probecommit.studies.protocol import load_protocol


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    p = load_protocol()
    data = config_data(p.run_config("faults_base", "B", "B_test_random", "random"))
    data["instances"] = {**data["instances"], "count": 6}
    data["repeats"], data["unit_instances"] = 2, 2
    data["belief"] = {**data["belief"], "particles": 64}
    data["simulator"] = {**data["simulator"], "engine": "analytic"}
    path = tmp_path_factory.mktemp("replay_final") / "base"
    run_study(parse_config(data), path, workers=1, threads=1)
    return load_run(path)


@pytest.mark.parametrize("overrides", [None, {"belief": {"likelihood": "mixture", "epsilon": 0.3, "mixture_low": -17.0,
                                                         "mixture_high": 2.0}},
                                       {"model": {"boundary": "corrected", "delta": 0.905}}])
@pytest.mark.parametrize("chunk", [48, 2])
def test_rows_at_the_budget_are_the_full_replays(base, overrides, chunk):
    full, _ = replay_episodes(base, overrides, chunk_instances=chunk)
    budgets = base.config.probes.commit_budgets
    for k in (max(budgets), min(budgets)):
        want = full[full["k"] == k].reset_index(drop=True)
        got = replay_at(base, overrides, k, chunk_instances=chunk)
        assert set(got["k"]) == {k}
        pd.testing.assert_frame_equal(got, want, check_exact=True)  # same rows, order, columns and dtypes


def test_a_budget_the_run_lacks_is_refused(base):
    with pytest.raises(UsageError):
        replay_at(base, None, max(base.config.probes.commit_budgets) + 1)


def test_e71_tuning_at_the_final_budget_is_the_full_tuning(base):
    """ex7's dev-draw tuning commits only the final budget: the table ``tune_robust_filters`` gives, bit for bit."""
    from probecommit.studies.explain.ex7_robust import tune_at_final
    from probecommit.studies.robust import robust_candidates, tune_robust_filters

    r = load_protocol().robust
    grid = robust_candidates([1.0, 16.0, 256.0], [0.01, 0.6, 0.99], [0.05, 0.5], r.mixture_range)
    want = tune_robust_filters(base, grid, chunk_instances=48).drop(columns="belief")
    got = tune_at_final(base, grid)
    assert want["failure"].nunique() > 1  # the grid's candidates differ: the check can fail
    pd.testing.assert_frame_equal(got, want, check_exact=True)


def test_e107_rows_are_the_full_replays_rows(base):
    """ex13's mixture rows, computed from final-budget replays, equal those of full replays."""
    from probecommit.studies.explain import ex13_mixture

    k, seeds = max(base.config.probes.commit_budgets), [base.config.seed, base.config.seed + 1]
    _, got = ex13_mixture.run(base, 0.3, -17.0, 2.0, seeds, k)
    rows = []
    for seed in seeds:
        loaded = ex13_mixture.reseeded(base, seed)
        right = ex13_mixture._final(replay_episodes(loaded, None, chunk_instances=48)[0], k)
        for reading in ex13_mixture.READINGS:
            eff = ex13_mixture.effective_epsilon(reading, 0.3, 19.0, float(base.config.model.sigma))
            belief = {"likelihood": "mixture", "epsilon": eff, "mixture_low": -17.0, "mixture_high": 2.0}
            mixed = ex13_mixture._final(replay_episodes(loaded, {"belief": belief}, chunk_instances=48)[0], k)
            rows.append((float(right["realized"].mean()), float(mixed["realized"].mean()),
                         float((right["action"].to_numpy() != mixed["action"].to_numpy()).mean())))
    assert list(zip(got["right"], got["mixed"], got["changed"])) == rows


def test_fault_cells_on_a_draw_are_the_full_harness_cells(base):
    """The fault harness's arms on a fresh draw, replayed at the final budget only, give the full harness's cells."""
    import math

    from probecommit.studies.explain import draw_faults
    from probecommit.studies.faults import fault_arms, run_fault_harness

    p = load_protocol()
    f, k = p.faults, max(base.config.probes.commit_budgets)
    arms = [a for a in fault_arms(f.noise_factor, f.prior_half_width, 16, f.frame_offset, f.temperature, p.sigma)
            if a.rollout == "base" and a.fault in draw_faults.FAULTS]
    want = draw_faults.arm_cells(run_fault_harness({"base": base}, arms, chunk_instances=48), k)
    got = draw_faults.arm_cells(draw_faults.harness_at(base, arms, k), k)
    assert {"none.fail", "boundary.fail", "particles.fail"} <= set(want)
    assert got.keys() == want.keys()
    assert all(got[c] == want[c] or (math.isnan(got[c]) and math.isnan(want[c])) for c in want)
