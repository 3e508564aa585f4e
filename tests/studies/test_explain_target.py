"""`reproduce explain --quick` end to end: every group written, and the numbers it recomputes from
stored runs equal the ones the insertion study computed its own way (same data, two paths)."""

from __future__ import annotations

import json

import pytest

from probecommit.report import paper


def test_explain_is_a_target_after_what_it_reads():
    order = paper.resolve(["explain"])
    assert order[-1] == "explain" and {"insertion", "engines", "gru"} <= set(order)


@pytest.mark.slow
def test_reproduce_explain_quick(tmp_path):
    from probecommit.studies.explain import reproduce_explain

    paper.reproduce(["insertion", "engines"], tmp_path, quick=True)
    folder = reproduce_explain(tmp_path, quick=True)
    res = json.loads((folder / "results.json").read_text())["results"]
    for group in ("missing", "committed_pool", "instance_generator", "margin_per_gamma", "thresholds", "gru",
                  "physx_capture", "boundary_fault", "robust"):
        assert res[group], group
    ins = json.loads((tmp_path / "insertion" / "results" / "results.json").read_text())["results"]
    ti = ins["table_insertion"]
    # The per-gamma rule over every gamma picks the margin the insertion study's search stopped at.
    assert res["margin_per_gamma"]["ours.gamma"] == ti["margin_cover"]
    assert res["thresholds"]["ours.t_5"] == ti["thresholds_cover"]["5"]
    assert res["thresholds"]["ours.distribution_free_margin"] == pytest.approx(ti["distribution_free_margin_cover"], abs=1e-12)
    # Thresholds from the stored scores equal calibrate()'s re-executed ones.
    assert res["thresholds"]["simultaneous_random_original_recomputed"] == ti["simultaneous_random"]
    corrected = ins["table_testc"]["failure_cover_k5_setcal_margin"]["simultaneous_threshold"]["corrected"]
    assert res["thresholds"]["simultaneous_cover_corrected_recomputed"] == corrected
    # The raw gate's pool read from the stored run equals the insertion study's re-executed gate.
    raw = next(r for r in ins["gates"]["summary"] if r["signal"] == "raw")
    assert res["committed_pool"]["ours.final_hull.escaped_committed"] == raw["escaped_committed"]
    assert res["committed_pool"]["ours.final_hull.escaped_rejected"] == raw["escaped_rejected"]
    # E211's gates recomputed on the paper's-schedule runs give the raw pool E13 reads from the stored run (ex37).
    for side in ("committed", "rejected"):
        assert res["ex37_adjusted"][f"raw.escaped_{side}"] == \
            res["committed_pool"][f"paper_schedule.final_hull.escaped_{side}"]
    assert res["ex37_adjusted"]["raw.n_committed"] == res["committed_pool"]["paper_schedule.n_committed"]
    assert res["ex37_filters"]["testc.deployed.optimism"] == pytest.approx(res["robust"]["testc.deployed.optimism"])
    # E232's check arm (Table III's run re-committed at the published t_k and margin) gives Table III's calibrated
    # cells (ex43).
    from probecommit.studies.explain import ex43_setonly

    assert ex43_setonly.check_published(res["ex43_setonly"], ins["table_audit"]["table"]) == []
    # The emulated engine's stored outcomes equal the capture rule recomputed from its aims.
    for variant in ("deployed", "mj_offset", "own_scan"):
        assert res["physx_capture"][f"emulated.{variant}.stored_equals_recomputed"] == 1
    # Table III's original cells on the analytic stand-in for Split B test equal the MuJoCo run's (ex1, E17).
    gen = res["instance_generator"]
    for row in ins["table_audit"]["table"]:
        for col in ("cluster_coverage", "optimism"):
            assert gen[f"draws.audit_check.{col}.original.k{row['k']}"] == pytest.approx(row[f"{col}_original"], abs=1e-12)
    # The surprise recomputed from the stored beliefs gives the stored statistic's AUC (E16's density reading).
    k = max(int(key.rsplit("_k", 1)[1]) for key in res["missing"] if key.startswith("surprise_auc_cover_k"))
    if res["missing"][f"surprise_auc_cover_k{k}"] is not None:
        assert res["missing"][f"surprise_variants.ours.density.final_hull.k{k}"][0] == pytest.approx(
            res["missing"][f"surprise_auc_cover_k{k}"][0], abs=1e-12)
    assert res["gru"]["available"] == 0  # the GRU target did not run here
    assert (folder / "explain.md").read_text().count("explain:results.") > 100
