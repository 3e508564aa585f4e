"""audit_table on a hand example: every metric, grouping, determinism."""

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.io import validate_episodes
from probecommit.audit.metrics import audit_from_sums, audit_table, instance_sums, summary_row


def _hand():
    # 2 instances x 2 repeats at k = 2, two methods; z_true = 0 everywhere.
    rows = []
    spec = {  # (inst, rep): (retained, hull, predicted, realized)
        ("a", 0): ((-1, 1), (-2, 2), 0.1, 0), ("a", 1): ((0.5, 1), (-2, 2), 0.2, 1),
        ("b", 0): ((-1, 0), (-1, 3), 0.0, 0), ("b", 1): ((-3, -1), (-3, -0.5), 0.3, 1),
    }
    for method, shift in (("probe_robust", 0.0), ("blind_robust", 10.0)):
        for (i, r), ((rlo, rhi), (hlo, hhi), p, y) in spec.items():
            rows.append({"instance_id": i, "repeat": r, "k": 2, "method": method, "variant": "deployed",
                         "predicted": p, "realized": y, "z_true": shift, "retained_lo": rlo, "retained_hi": rhi,
                         "hull_lo": hlo, "hull_hi": hhi})
    return validate_episodes(pd.DataFrame(rows))


def test_hand_example_every_metric():
    a = audit_table(_hand(), resamples=500).set_index("method")
    p = a.loc["probe_robust"]
    assert p["coverage"] == pytest.approx(0.5)  # a0 and b0 cover 0; a1 [0.5, 1] and b1 miss
    assert p["cluster_coverage"] == pytest.approx(0.0)  # neither instance covered in both repeats
    assert p["escape"] == pytest.approx(0.25)  # b1: hull [-3, -0.5]
    assert p["realized"] == pytest.approx(0.5)
    assert p["predicted"] == pytest.approx(0.15)
    assert p["optimism"] == pytest.approx(0.35)
    assert (p["n_episodes"], p["n_instances"], p["n_repeats"], p["n_failed"]) == (4, 2, 2, 0)
    # Bootstrap bounds: two instances with coverage 1/2 each -> every resample is 1/2.
    assert p["coverage_lo"] == p["coverage_hi"] == pytest.approx(0.5)
    # Escape: instance a 0/2, b 1/2 -> resamples give 0, 1/4 or 1/2.
    assert p["escape_lo"] == pytest.approx(0.0) and p["escape_hi"] == pytest.approx(0.5)
    b = a.loc["blind_robust"]
    assert b["coverage"] == 0.0 and b["escape"] == 1.0  # z_true = 10 is outside everything


def test_deterministic_given_seed_and_independent_of_other_groups():
    t = _hand()
    a1 = audit_table(t, resamples=200, seed=5)
    a2 = audit_table(t, resamples=200, seed=5)
    pd.testing.assert_frame_equal(a1, a2)
    alone = audit_table(t[t.method == "probe_robust"], resamples=200, seed=5)
    pd.testing.assert_frame_equal(alone.reset_index(drop=True),
                                  a1[a1.method == "probe_robust"].reset_index(drop=True))


def test_failed_rows_are_excluded_and_counted_and_budgets_filter():
    t = _hand()
    t.loc[1, ["realized", "status"]] = [np.nan, "failed"]
    a = audit_table(t, resamples=100).set_index("method").loc["probe_robust"]
    assert a["n_episodes"] == 3 and a["n_failed"] == 1
    assert a["realized"] == pytest.approx(1 / 3)
    assert a["cluster_coverage"] == pytest.approx(0.5)  # a: its one ok repeat is covered
    assert audit_table(t, budgets=[5]).empty


def test_summary_row():
    a = pd.DataFrame({"cluster_coverage": [0.7, 0.9], "optimism": [0.1, -0.3]})
    assert summary_row(a) == pytest.approx({"mean_abs_cluster_coverage_gap": 0.1, "mean_abs_optimism": 0.2})


def _random_table(seed: int = 3, instances: int = 23) -> pd.DataFrame:
    # Two methods, three budgets, uneven repeats, realized and predicted with long fractions, some failed rows,
    # and a "rollout" group whose every row failed (trajectories whose probing failed).
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(instances):
        for r in range(int(rng.integers(1, 4))):
            for method in ("probe_robust", "blind_robust"):
                for k in (1, 3, 5):
                    lo = rng.normal()
                    rows.append({"instance_id": f"i{i:03d}", "repeat": r, "k": k, "method": method,
                                 "variant": "deployed", "predicted": rng.random() / 3, "realized": rng.random(),
                                 "z_true": rng.normal(), "retained_lo": lo, "retained_hi": lo + rng.random(),
                                 "hull_lo": lo - 1, "hull_hi": lo + 2, "status": "ok"})
    table = pd.DataFrame(rows)
    failed = rng.random(len(table)) < 0.08
    table.loc[failed, ["status", "realized"]] = ["failed", np.nan]
    rollout = {"instance_id": "i007", "repeat": 9, "k": 0, "method": "rollout", "variant": "deployed", "status": "failed"}
    return validate_episodes(pd.concat([table, pd.DataFrame([rollout])], ignore_index=True), structure=False)


@pytest.mark.parametrize("budgets", [None, [1, 5]])
def test_audit_from_sums_of_instance_parts_is_the_whole_tables_audit(budgets):
    # The calibration keeps only each chunk's per-instance sums: whole instances per part, rows in
    # order, the rollout rows last, as runner.calibration concatenates them.
    table = _random_table()
    whole = audit_table(table, budgets=budgets, resamples=300, seed=4)
    ids = table["instance_id"]
    parts = [table.loc[(table.method != "rollout") & ids.isin(chunk)] for chunk in
             (["i000", "i001", "i002"], [f"i{i:03d}" for i in range(3, 17)], [f"i{i:03d}" for i in range(17, 23)])]
    parts.append(table.loc[table.method == "rollout"])
    sums = [instance_sums(part) for part in parts]
    joined = audit_from_sums(pd.concat([s for s, _ in sums]), pd.concat([f for _, f in sums]), budgets=budgets,
                             resamples=300, seed=4)
    pd.testing.assert_frame_equal(joined, whole, check_exact=True)
    assert whole["n_failed"].min() >= 1  # the rollout trajectory is counted at every budget


def test_instance_sums_by_hand():
    t = _hand()
    t.loc[1, ["realized", "status"]] = [np.nan, "failed"]
    sums, failed = instance_sums(t)
    row = sums.set_index(["method", "instance_id"]).loc[("probe_robust", "a")]
    assert (row["n"], row["covered"], row["realized"], row["n_repeats"], row["n_failed"]) == (1, 1, 0, 1, 1)
    assert failed[["instance_id", "repeat", "method"]].values.tolist() == [["a", 1, "probe_robust"]]
