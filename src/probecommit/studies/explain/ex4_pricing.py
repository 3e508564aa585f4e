"""Do the paper's break-even prices follow from the paper's own curve by our pricing rule (E48)?

Why: a family's two prices (Sec. III) are a function of three points of one executor's
miss-versus-budget curve, Blind-Robust at k = 0 (``m0``) and Probe-Robust at k = 2 and 5
(``m2``, ``m5``): :func:`probecommit.studies.pricing.break_even`. Our prices differ from the
paper's; the question is whether that is a difference of definition or only of curve. The
paper prints ``m5`` for every priced family (Table II's Probe-Robust cell), ``m0`` for darts
and 2-D push only, and ``m2`` never. So we search for a curve that agrees with every printed
cell to its rounding, is monotone, keeps an unprinted ``m0`` at or above the printed
Blind-Bayes cell, and gives both of the paper's prices within the claim's tolerance through
our ``break_even``. If one exists, the paper's prices are what our rule makes of the paper's
curve, and our price difference is the curve difference of Table II (docs/decisions.md,
"ex4"). The same search with Blind-Bayes read as the k = 0 point says whether the rule's
choice of blind arm is pinned down by the paper's numbers.

No run and no stored rows: the inputs are the paper's printed values, the outputs a pure
function of them (verify recomputes the keys by calling :func:`keys` again).
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: The priced families (Sec. III), in the paper's order.
FAMILIES = ("darts", "push2d", "hinge", "push1d")
#: Printed Table II cells are rounded to three decimals.
ROUNDING = 0.0005
#: The claim's own tolerance on a price (T01-pricing: within 10 %).
TOLERANCE = 0.10
#: Upper end of an unprinted m0 (m or rad) and the grid steps (docs/decisions.md).
M0_MAX, M0_STEP_FREE, M2_STEP_PRINTED, M2_STEP_FREE = 4.0, 0.001, 0.0001, 0.0005


def break_even_grid(m0: np.ndarray, m2: np.ndarray, m5: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`probecommit.studies.pricing.break_even`'s two prices, elementwise over broadcast arrays."""
    m0, m2, m5 = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (m0, m2, m5)))
    chord = np.maximum((m0 - m5) / 5, 0.0)
    convex = ~((m0 - m2) / 2 < (m2 - m5) / 3)
    blind = np.where(convex, np.maximum(np.maximum((m0 - m2) / 2, (m0 - m5) / 5), 0.0), chord)
    five = np.where(convex, np.maximum(np.minimum((m2 - m5) / 3, (m0 - m5) / 5), 0.0), chord)
    return blind, five


def _around(v: float, points: int) -> np.ndarray:
    return np.linspace(v - ROUNDING, v + ROUNDING, points)


def consistent_curves(prices: tuple[float, float], m5: float, m0: float | None, m0_floor: float,
                      tolerance: float = TOLERANCE) -> dict[str, float]:
    """Whether a curve gives both ``prices`` (blind above, five below) within ``tolerance`` (relative).

    ``m0`` printed (within rounding) or None (free, from ``m0_floor`` to ``M0_MAX``); ``m5`` printed;
    ``m2`` free between them. Returns ``consistent`` (0/1), how many grid curves pass, and the range
    of ``m2`` (and of ``m0``) over the passing curves (NaN when none).
    """
    m5s = np.clip(_around(m5, 3), 0.0, None)
    b_p, f_p = prices
    if m0 is None:  # a curve with (m0 - m5) / 5 above the blind price's tolerance fails it (blind >= that chord)
        top = min(M0_MAX, m5 + ROUNDING + 5 * (1 + tolerance) * b_p + M0_STEP_FREE)
        m0s, step = np.arange(max(m0_floor - ROUNDING, 0.0), top + 1e-12, M0_STEP_FREE), M2_STEP_FREE
    else:
        m0s, step = _around(m0, 11), M2_STEP_PRINTED
    m2s = np.arange(0.0, m0s.max() + step / 2, step)
    hits, m2_hit, m0_hit = 0, [], []
    for a in m5s:
        for start in range(0, len(m0s), 128):  # bounded memory: 128 rows of m0 at a time
            M0, M2 = m0s[start:start + 128, None], m2s[None, :]
            blind, five = break_even_grid(M0, M2, a)
            ok = ((M0 >= M2) & (M2 >= a) & (np.abs(blind - b_p) <= tolerance * b_p + 1e-12)
                  & (np.abs(five - f_p) <= tolerance * f_p + 1e-12))
            hits += int(ok.sum())
            i, j = np.nonzero(ok)
            m0_hit.extend(M0[i, 0].tolist())
            m2_hit.extend(m2s[j].tolist())
    nan = float("nan")
    return {"consistent": float(hits > 0), "curves": float(hits),
            "m2_lo": min(m2_hit, default=nan), "m2_hi": max(m2_hit, default=nan),
            "m0_lo": min(m0_hit, default=nan), "m0_hi": max(m0_hit, default=nan)}


def family_keys(family: str, cells: dict[str, float], prices: tuple[float, float]) -> dict[str, float]:
    """One family's keys: the search with Blind-Robust at k = 0 (the paper's rule), and with Blind-Bayes
    where both blind cells are printed (the other reading). ``cells``: the printed Table II cells."""
    out = {f"{family}.{k}": v for k, v in consistent_curves(
        prices, cells["probe_robust"], cells.get("blind_robust"), cells["blind_bayes"]).items()}
    out[f"{family}.m0_printed"] = float("blind_robust" in cells)
    if "blind_robust" in cells:
        alt = consistent_curves(prices, cells["probe_robust"], cells["blind_bayes"], cells["blind_bayes"])
        out[f"{family}.blind_bayes_reading.consistent"] = alt["consistent"]
    return out


def keys() -> dict[str, Any]:
    """Keys of ``explain:results.ex4_pricing`` from the paper's printed values (in the miss's units)."""
    from probecommit.studies.explain.breadth import paper_cells

    out: dict[str, Any] = {}
    for family in FAMILIES:
        cells = paper_cells(family)
        prices = (cells.pop("price.blind_above"), cells.pop("price.five_below"))
        out.update(family_keys(family, cells, prices))
    return out
