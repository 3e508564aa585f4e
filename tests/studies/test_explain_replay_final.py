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
