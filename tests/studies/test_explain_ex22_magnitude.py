"""ex22's E158 (the hinge's probe magnitudes swept): the ratio's paired bootstrap on hand cases, the keys on hand-built
rows with exact answers (the ratio's teeth), the claim's wiring and the stored rows' round trip."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex22_magnitude as em

from .recompute_contract import assert_round_trip


def _paper() -> tuple[float, float]:
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    return value("tab:breadth.hinge.probe_robust"), implied_k2("hinge")


def _rows(cells: dict[str, tuple[float, float]], spread: float = 0.0) -> pd.DataFrame:
    """Per part, two instances x two repeats per budget; instance b's misses are ``1 + spread`` times a's (so the
    ratio is the same in every resample and the cells' intervals widen with ``spread``)."""
    rows = []
    for part, (k2, k5) in cells.items():
        for k, miss in ((2, k2), (5, k5)):
            for inst, f in (("a", 1.0), ("b", 1.0 + spread)):
                rows += [{"part": part, "instance_id": inst, "repeat": r, "k": k, "realized": miss * f} for r in (0, 1)]
    return pd.DataFrame(rows)


def test_ratio_interval_is_exact_when_every_instance_has_the_same_ratio():
    rows = _rows({"x": (0.3, 0.1)}, spread=1.0)[lambda t: t.part == "x"]
    r, lo, hi = em.ratio_interval(rows)
    assert (r, lo, hi) == pytest.approx((3.0, 3.0, 3.0))
    mixed = pd.DataFrame({"instance_id": ["a", "a", "b", "b"], "k": [2, 5, 2, 5], "realized": [2.0, 1.0, 1.0, 1.0]})
    r, lo, hi = em.ratio_interval(mixed)
    assert r == pytest.approx(1.5) and lo == pytest.approx(1.0) and hi == pytest.approx(2.0)


def test_keys_need_both_cells_and_the_ratio_at_one_scale():
    p5, p2 = _paper()
    base = {"stored": (0.1, 0.07), "c100": (0.1, 0.07)}
    wrong_ratio = {**base, **{em.label(c): (p2, p2 / 1.5) for c in em.SCALES[1:]}}  # k2 exact, k5 off, ratio 1.5
    k = em.keys(_rows(wrong_ratio, spread=0.5))
    assert k["premise_holds"] == 1 and k["c150.ratio_k2_k5"] == pytest.approx(1.5)
    assert k["c150.k2_paper_inside"] == 1 and k["c150.ratio_paper_inside"] == 0 and k["holds"] == 0
    right = {**wrong_ratio, "c175": (p2, p5)}
    k = em.keys(_rows(right))
    assert k["holds"] == 1 and k["scales_holding"] == 1 and k["first_scale"] == 1.75 and k["c175.holds"] == 1
    off = em.keys(_rows({**right, "c100": (0.1, 0.07 * 1.06)}))  # premise 6 % > 5 %
    assert off["premise_holds"] == 0 and off["holds"] == 0


def test_e158_speaks_to_the_hinge_probe_cell():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E158"] == ("hinge probe_robust",)
    e = claims.EXPERIMENTS["E158"]
    assert e.supports({"ok": 1, "holds": 1, "h": 1}) and not e.supports({"ok": 1, "holds": 0, "h": 0})


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex22

    p5, p2 = _paper()
    rows = _rows({"stored": (0.1, 0.07), "c100": (0.1, 0.07), **{em.label(c): (p2, p5) for c in em.SCALES[1:]}})
    keys = em.keys(rows)
    values, sources, problems = ex22.recompute(tmp_path, {"ex22_magnitude": keys})
    assert problems  # published without its rows
    assert_round_trip(tmp_path, ex22.recompute, "ex22_magnitude", em.STORED, rows, keys)
