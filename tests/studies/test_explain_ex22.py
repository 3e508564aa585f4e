"""ex22's E156/E157 (Table II's push1d and hinge Probe-Robust cells on the exact posterior of the stored readings):
the pruned scenario minimax against the executor itself, the exact retained prefix against ``core.retained``, the
keys on hand-built rows with exact answers (each premise's and each paper point's teeth), the claim's wiring and the
stored rows' round trip."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex22_exact as ex

from .recompute_contract import assert_round_trip


def _model(family: str):
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config

    return build_model(paper_config(family))


@pytest.mark.parametrize("family", ["push1d", "hinge"])
def test_minimax_index_is_the_executors_choice(family):
    from probecommit.core.executors import ProbeRobust, RetainedSet
    from probecommit.core.retained import belief_reference

    model, rng = _model(family), np.random.default_rng(5)
    for t in range(25):
        points = ex.prior_sample(model, 300, seed=t)
        centre = points.mean(axis=0)
        points = (points - centre) * rng.uniform(0.02, 1.0) + centre  # sets from nearly a point to the whole box
        w = rng.random(len(points))
        w /= w.sum()
        target = float(rng.choice([0.5, 1.0, 1.5]))
        chosen = ProbeRobust(model).choose(RetainedSet(points[None], np.ones((1, len(points)), bool), np.zeros(1),
                                                       np.ones(1), belief_reference(points[None], w[None])),
                                           np.array([[target]]))
        assert ex.minimax_index(model, points, w, target) == int(chosen.index[0])


def test_exact_retained_is_the_top_weight_prefix():
    from probecommit.core.retained import retained_mask

    rng = np.random.default_rng(3)
    log_w = rng.normal(0, 3, 2000)
    log_w[:10] = log_w[10]  # ties, kept in index order
    kept, w = ex.exact_retained(log_w, 0.8)
    full = np.exp(log_w - log_w.max())
    full /= full.sum()
    assert set(kept) == set(np.flatnonzero(retained_mask(full[None], 0.8)[0]))
    assert np.allclose(w, full[kept]) and np.all(np.diff(w) <= 0)
    assert full[kept[:-1]].sum() < 0.8 <= full[kept].sum() + 1e-12


def _rows(family: str, cells: dict[tuple[str, int], float]) -> pd.DataFrame:
    """Two instances x two repeats per budget and part, every episode the part's cell (exact, zero-width intervals)."""
    rows = []
    for (part, k), miss in cells.items():
        for inst in ("a", "b"):
            for rep in (0, 1):
                rows.append({"family": family, "instance_id": inst, "repeat": rep, "k": k, "sample": 64.0,
                             "part": part, "action": 1.0 if part != "exact" else 1.0 + rep, "realized": miss,
                             "kept": 10.0 + k if part.startswith("exact") else np.nan})
    return pd.DataFrame(rows)


def _paper(family: str) -> tuple[float, float]:
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    return value(f"tab:breadth.{family}.probe_robust"), implied_k2(family)


def _cells(family: str, **change: float) -> dict[tuple[str, int], float]:
    p5, p2 = _paper(family)
    cells = {("stored", 2): 0.12, ("stored", 5): 0.08, ("model", 2): 0.12, ("model", 5): 0.08,
             ("exact", 2): p2, ("exact", 5): p5, ("exact_quarter", 2): p2, ("exact_quarter", 5): p5}
    for name, v in change.items():
        part, k = name.rsplit("_k", 1)
        cells[(part, int(k))] = v
    return cells


@pytest.mark.parametrize("family", ["push1d", "hinge"])
def test_keys_hold_at_the_papers_points_and_each_condition_has_teeth(family):
    p5, p2 = _paper(family)
    k = ex.family_keys(_rows(family, _cells(family)), family)
    assert k["holds"] == 1 and k["premises_hold"] == 1
    assert k["exact.k5"] == pytest.approx(p5) and k["paper.ratio_k2_k5"] == pytest.approx(p2 / p5)
    assert k["same_action_share"] == 0.5 and k["exact.k5_median_kept"] == 15 and k["episodes"] == 4
    assert ex.family_keys(_rows(family, _cells(family, exact_k5=p5 * 1.5, exact_quarter_k5=p5 * 1.5)),
                          family)["exact.k5_paper_inside"] == 0
    assert ex.family_keys(_rows(family, _cells(family, exact_k2=p2 * 0.5, exact_quarter_k2=p2 * 0.5)),
                          family)["holds"] == 0
    off = ex.family_keys(_rows(family, _cells(family, exact_quarter_k5=p5 * 1.1)), family)  # 10 % > 3 %
    assert off["premise_convergence_rel_diff"] == pytest.approx(0.1) and off["holds"] == 0
    model_off = 1.0 + 2 * ex.FAMILIES[family]
    assert ex.family_keys(_rows(family, _cells(family, model_k5=0.08 * model_off)), family)["premises_hold"] == 0


def test_e156_e157_speak_to_the_probe_cells_and_supports_reads_the_rule():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E156"] == ("push1d probe_robust",) and spoken["E157"] == ("hinge probe_robust",)
    e = claims.EXPERIMENTS["E156"]
    assert e.supports({"ok": 1, "in5": 1, "in2": 1})
    assert not any(e.supports({"ok": a, "in5": b, "in2": c}) for a, b, c in ((0, 1, 1), (1, 0, 1), (1, 1, 0)))


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex22

    rows = pd.concat([_rows("push1d", _cells("push1d")), _rows("hinge", _cells("hinge", exact_k5=0.05))],
                     ignore_index=True)
    keys = ex.keys(rows)
    assert keys["push1d.holds"] == 1 and keys["hinge.holds"] == 0
    values, sources, problems = ex22.recompute(tmp_path, {"ex22_exact": keys})
    assert problems  # published without its rows
    assert_round_trip(tmp_path, ex22.recompute, "ex22_exact", ex.STORED, rows, keys)


def test_replay_on_a_tiny_stored_run_reproduces_a_hand_posterior():
    """Two prior points, one reading: the posterior keeps the point the reading favours (its weight > 0.8), and
    the action is the one whose outcome at that point is nearest the target, its miss from the model."""
    model = _model("push1d")
    sample = np.array([[0.25, 1.0, 1.0], [0.55, 1.0, 1.0]])
    u = float(model.probe_grid[1, 0])
    y = float(model.outcome(np.array([u]), *sample[0][:, None])[0])
    probes = pd.DataFrame({"instance_id": ["a"], "repeat": [0], "j": [1], "u": [u], "y": [y]})
    episodes = pd.DataFrame({"instance_id": ["a"], "repeat": [0], "k": [1], "ctx_target": [1.0], "true_mu": [0.25],
                             "true_m": [1.0], "true_k_d": [1.0]})
    out = ex.replay(model, sample, probes, episodes, 0.8)
    grid = np.asarray(model.action_grid, float)[:, 0]
    d = model.outcome(grid, *[np.full(len(grid), v) for v in sample[0]])
    assert out["kept"][0] == 1 and out["action"][0] == grid[np.argmin(np.abs(d - 1.0))]
    assert out["realized"][0] == pytest.approx(np.min(np.abs(d - 1.0)))
