"""Hand cases for the second explain helper's experiments (E31..E44): the prior sweep's config
transform and span summary, and the claims registry wiring them."""

from __future__ import annotations

import re

import math

import pytest

from probecommit.studies import claims
from probecommit.studies.breadth import paper_config
from probecommit.studies.explain.breadth import paper_cells, scaled_config, span_summary


def test_scaled_config_keeps_truths_at_their_relative_position():
    base = paper_config("push1d")
    half = scaled_config(base, 0.5, engine="analytic", repeats=2)
    assert half.model.prior_low == pytest.approx([0.3, 0.75, 1.125])
    assert half.model.prior_high == pytest.approx([0.5, 1.25, 2.375])
    # (0.25, 0.625, 0.8125) sits at 1/8 of each width; it stays at 1/8 of the narrower prior.
    assert list(half.instances.truths[0]) == pytest.approx([0.325, 0.8125, 1.28125])
    assert half.repeats == 2 and half.simulator.engine == "analytic" and half.name == "push1d_prior0.5"
    same = scaled_config(base, 1.0)
    assert same.model.prior_low == pytest.approx(list(base.model.prior_low))


def test_scaled_config_refuses_a_non_positive_latent():
    with pytest.raises(ValueError, match="non-positive"):
        scaled_config(paper_config("push1d"), 1.5)


def _row(bb, br, pr, paired_lo, **prices):
    r = {"blind_bayes": bb, "blind_bayes_lo": bb - 0.1, "blind_bayes_hi": bb + 0.1,
         "blind_robust": br, "blind_robust_lo": br - 0.1, "blind_robust_hi": br + 0.1,
         "probe_robust": pr, "probe_robust_lo": pr - 0.01, "probe_robust_hi": pr + 0.01,
         "paired": bb - pr, "paired_lo": paired_lo, "paired_hi": bb - pr + 0.1}
    r.update({f"price.{k}": v for k, v in prices.items()})
    return r


def test_span_summary_by_hand():
    rows = {0.5: _row(0.2, 0.3, 0.05, 0.1, blind_above=0.02, five_below=0.001),
            1.0: _row(0.6, 0.7, 0.09, 0.3, blind_above=0.1, five_below=0.004)}
    paper = {"blind_bayes": 0.75, "probe_robust": 0.2, "price.blind_above": 0.05, "price.five_below": 0.01}
    out = span_summary(rows, paper)
    assert (out["span.blind_bayes.lo"], out["span.blind_bayes.hi"]) == pytest.approx((0.1, 0.7))
    assert out["span.blind_bayes.paper_inside"] == 0.0  # 0.75 > 0.7
    assert out["span.probe_robust.paper_inside"] == 0.0  # 0.2 > 0.1
    assert out["span.price.blind_above.paper_inside"] == 1.0 and out["span.price.five_below.paper_inside"] == 0.0
    assert (out["cells_inside"], out["cells"], out["prices_inside"], out["prices"]) == (0.0, 2.0, 1.0, 2.0)
    assert out["min_paired_lo"] == 0.1 and out["probing_reduces_everywhere"] == 1.0
    rows[2.0] = _row(0.1, 0.1, 0.2, -0.2)
    out = span_summary(rows, {"probe_robust": 0.2})
    assert out["span.probe_robust.paper_inside"] == 1.0
    assert out["min_paired_lo"] == -0.2 and out["probing_reduces_everywhere"] == 0.0


def test_paper_cells_read_the_papers_row_and_prices_in_our_units():
    darts = paper_cells("darts")
    assert darts["blind_bayes"] == 0.026 and darts["probe_robust"] == 0.010
    assert darts["price.blind_above"] == pytest.approx(0.012) and darts["price.five_below"] == pytest.approx(0.0006)
    assert paper_cells("hinge")["price.five_below"] == pytest.approx(0.012)
    assert "price.blind_above" not in paper_cells("shuffleboard")


def test_ex2_experiments_are_numbered_30_to_49_and_wired_to_their_claims():
    mine = {n for n in claims.EXPERIMENTS if 30 <= int(re.match(r"E(\d+)", n).group(1)) <= 44}
    assert {"E30", "E31", "E32", "E33", "E34", *(f"E{i}" for i in range(35, 45))} == mine
    by_id = {c.id: c for c in claims.CLAIMS}
    wired = {e if isinstance(e, str) else e[0] for cid in ("tab:breadth", "T01-pricing", "T07-cover-schedule",
                                                           "T26-hardware-optimism", "T28-replay-boundary", "T18-engine-scans",
                                                           "T42-robust-chosen") for e in by_id[cid].explain}
    assert mine - {"E33"} <= wired  # E33's own pooled 4-tap interval excludes zero: not credited with T26 (credA)


def test_unresolved_choice_rule_by_hand():
    assert claims._unresolved_choice({"share": 0.05, "lo": -0.1, "hi": 0.2})
    assert not claims._unresolved_choice({"share": 0.04, "lo": -0.1, "hi": 0.2})
    assert not claims._unresolved_choice({"share": 0.3, "lo": 0.01, "hi": 0.2})


def test_a_breadth_experiment_that_does_not_bear_its_cause_out_explains_nothing():
    e = claims.EXPERIMENTS["E38"]
    good = {"n": 5, "inside": 3.0, "cells": 3.0, "mpl": 0.01, "red": 1.0, "one": 3.0, "at": 1.0, "all": 1.0}
    assert e.supports(good)
    assert not e.supports({**good, "inside": 2.0})
    assert not e.supports({**good, "mpl": -0.001})
    assert not e.supports({**good, "red": 0.0})
    assert not math.isnan(good["mpl"])


def test_mean_interval_by_hand():
    from probecommit.studies.explain.engines_x import mean_interval

    mean, lo, hi = mean_interval(1.21, 0.69, 24)
    assert mean == 1.21
    assert hi - mean == pytest.approx(1.959963984540054 * 0.69 / 24 ** 0.5)
    assert (lo, hi) == pytest.approx((0.934, 1.486), abs=1e-3)


@pytest.mark.slow
def test_rig_redraw_at_the_frozen_seed_gives_the_robot_studys_numbers(tmp_path):
    """Two paths, one answer: a "redraw" at the frozen positions' seed is the robot study's own session."""
    from probecommit.audit.stats import DEFAULT_SEED
    from probecommit.studies.explain import rig
    from probecommit.studies.robot import rig_config, run_robot_study

    boot = {"resamples": 200, "seed": DEFAULT_SEED}
    frozen_seed = int(rig_config(quick=True).instances.seed)
    sessions = rig.redrawn_sessions(tmp_path / "redraws", [frozen_seed], quick=True)
    study = run_robot_study(tmp_path / "study", quick=True, resamples=200)
    opt, table = rig.optimism_redraws(sessions, boot)
    assert opt["sessions"] == 1
    own = study.table.set_index("taps")["optimism"]
    assert table.set_index("taps")["optimism"].to_dict() == pytest.approx(own.to_dict())
    sizes = rig.BOUNDARY_SWEEP[::7]
    b = rig.boundary_redraws(sessions, boot, sizes)
    payload = study.payload()["results"]
    assert b["coverage_holds_to_mm.median"] == payload["boundary_holds_to_mm"]
    if payload["boundary_first_resolved_mm"] is not None:
        assert b["first_resolved_mm.median"] == payload["boundary_first_resolved_mm"]
