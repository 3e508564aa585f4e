"""ex11's explain experiments (E94, E95): hand cases, exact answers, the rule's teeth, the stored rows' round trip."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex11_probe as ep

from .recompute_contract import assert_round_trip


def _rows(family: str, stored: dict[str, float], scene: dict[str, float], pool: dict[str, float],
          seeds: int = 3) -> pd.DataFrame:
    """Stored rows with every episode of a truth at that truth's miss (so per-truth means are exact)."""
    rows = []
    for part, truths in (("stored", stored), ("scene", scene), ("pool", pool)):
        for t, miss in truths.items():
            rows += [{"family": family, "part": part, "truth": t, "instance_id": t, "repeat": r, "realized": miss}
                     for r in range(seeds)]
    return pd.DataFrame(rows)


def test_pool_truths_are_seeded_and_inside_the_prior_box():
    low, high = np.array([0.2, 0.1, 2.0]), np.array([0.8, 0.5, 6.0])
    a, b = ep.pool_truths(low, high, 36), ep.pool_truths(low, high, 36)
    assert a.shape == (36, 3) and np.array_equal(a, b)
    assert (a >= low).all() and (a <= high).all()
    assert not np.array_equal(a, ep.pool_truths(low, high, 36, seed=1))


def test_redraws_are_means_of_pool_truths_drawn_with_replacement():
    means = np.array([0.0, 1.0, 10.0])
    cells = ep.redraw_cells(means, n_truths=2, draws=7, seed=5)
    pick = np.random.default_rng(5).integers(0, 3, size=(7, 2))
    assert cells == pytest.approx(means[pick].mean(axis=1), abs=0)
    assert np.all(ep.redraw_cells(np.array([0.25, 0.25]), 6, 10) == 0.25)  # one value: every redraw is it


def test_per_truth_means_weigh_every_episode_of_a_truth_equally():
    rows = pd.DataFrame({"truth": ["a", "a", "a", "b"], "realized": [0.0, 0.0, 0.3, 0.5]})
    assert ep.per_truth(rows).to_dict() == pytest.approx({"a": 0.1, "b": 0.5})


def test_keys_put_the_papers_cell_inside_or_outside_the_redraws():
    paper = 0.031  # tab:breadth.hinge.probe_robust
    inside = ep.keys(_rows("hinge", {"x": 0.08, "y": 0.07}, {"x": 0.08, "y": 0.07},
                           {"p": 0.02, "q": 0.03, "r": 0.04}), draws=500)
    assert inside["hinge.n_truths"] == 2 and inside["hinge.pool_truths"] == 3 and inside["hinge.draws"] == 500
    assert inside["hinge.stored"] == pytest.approx(0.075) and inside["hinge.premise_holds"] == 1
    assert inside["hinge.pool.min"] == pytest.approx(0.02) and inside["hinge.pool.max"] == pytest.approx(0.04)
    assert inside["hinge.draws.p025"] == pytest.approx(0.02) and inside["hinge.draws.p975"] == pytest.approx(0.04)
    assert inside["hinge.paper"] == paper and inside["hinge.paper_inside"] == 1
    # the paper lies below ours: the share toward it counts the redraws at or below 0.031
    assert 0 < inside["hinge.share_toward_paper"] < 1
    outside = ep.keys(_rows("hinge", {"x": 0.08}, {"x": 0.08}, {"p": 0.06, "q": 0.09}), draws=200)
    assert outside["hinge.paper_inside"] == 0 and outside["hinge.share_toward_paper"] == 0


def test_premise_fails_when_the_pools_scene_misses_the_stored_cell():
    out = ep.keys(_rows("push2d", {"x": 0.10}, {"x": 0.106}, {"p": 0.221}), draws=20)
    assert out["push2d.premise_rel_diff"] == pytest.approx(0.06) and out["push2d.premise_holds"] == 0
    assert out["push2d.paper_inside"] == 1  # the redraws alone would pass: the premise is what fails
    ok = ep.keys(_rows("push2d", {"x": 0.10}, {"x": 0.104}, {"p": 0.221}), draws=20)
    assert ok["push2d.premise_holds"] == 1


def test_experiments_support_only_with_the_premise_and_the_paper_inside():
    e = claims.EXPERIMENTS["E94"]
    assert e.supports({"ok": 1, "inside": 1}) and not e.supports({"ok": 0, "inside": 1})
    assert not claims.EXPERIMENTS["E95"].supports({"ok": 1, "inside": 0})
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E94"] == ("hinge probe_robust",) and spoken["E95"] == ("push2d probe_robust",)


def test_stored_rows_round_trip_through_verify(tmp_path):
    from probecommit.studies.explain import ex11

    rows = _rows("hinge", {"x": 0.08}, {"x": 0.08}, {"p": 0.02, "q": 0.05})
    assert_round_trip(tmp_path, ex11.recompute, "ex11_probe", ep.STORED, rows, ep.keys(rows, draws=40))


def test_no_breadth_runs_no_keys(tmp_path):
    keys, rows = ep.run(tmp_path, tmp_path / "runs", draws=10)
    assert keys == {} and rows.empty
