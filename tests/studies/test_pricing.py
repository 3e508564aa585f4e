"""Break-even probe prices on hand-made curves with known answers."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies.pricing import best_budget, break_even, pricing_table


def test_a_convex_curve_has_two_prices_with_two_probes_between():
    p = break_even(1.0, 0.4, 0.25)  # per-probe gains: 0.3 (first two), 0.05 (next three)
    assert p.blind_above == pytest.approx(0.3) and p.five_below == pytest.approx(0.05) and p.two_ever_optimal
    assert best_budget(1.0, 0.4, 0.25, 0.31) == 0
    assert best_budget(1.0, 0.4, 0.25, 0.2) == 2
    assert best_budget(1.0, 0.4, 0.25, 0.04) == 5


def test_a_non_convex_curve_never_picks_two_probes():
    p = break_even(1.0, 0.9, 0.2)  # two probes buy little, five buy a lot
    assert not p.two_ever_optimal and p.blind_above == p.five_below == pytest.approx(0.16)
    assert all(best_budget(1.0, 0.9, 0.2, lam) != 2 for lam in (0.0, 0.05, 0.1, 0.159, 0.161, 0.3))


def test_a_curve_that_worsens_with_probes_is_blind_at_every_price_and_ties_go_to_fewer_probes():
    assert break_even(0.1, 0.2, 0.3).blind_above == 0.0
    assert best_budget(1.0, 0.4, 0.25, 0.3) == 0  # J(0) = J(2) = 1.0: the smaller budget


def test_pricing_table_reads_breadth_curves():
    curves = pd.DataFrame({"family": "toy", "method": ["blind_robust", "probe_robust", "probe_robust"],
                           "k": [0, 2, 5], "mean": [1.0, 0.4, 0.25]})
    row = pricing_table(curves).iloc[0]
    assert row["blind_above"] == pytest.approx(0.3) and row["five_below"] == pytest.approx(0.05)
