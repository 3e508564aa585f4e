"""Probe pricing (paper Sec. III, "Probe protocol and cost").

On the frozen miss-versus-budget curve of one fixed executor (Blind-Robust at k = 0,
Probe-Robust at k in {2, 5}) a probe priced at ``lambda`` (in the loss's units per
probe) gives ``J_lambda(k) = miss(k) + lambda k``. Two break-even prices per family:

* ``blind_above``: above it a blind commit beats every budget,
  ``max((m0 - m2) / 2, (m0 - m5) / 5)``;
* ``five_below``: below it five probes are the optimum,
  ``min((m2 - m5) / 3, (m0 - m5) / 5)``.

Between the two, two probes are optimal. When the curve is not convex (two probes
buy less per probe than five: ``(m0 - m2) / 2 < (m2 - m5) / 3``), two probes are never
optimal and both prices equal ``(m0 - m5) / 5``. A price is clipped at zero (a curve
that gets worse with probes is blind-optimal at every price).
"""

from __future__ import annotations

from dataclasses import dataclass
import numpy as np
import pandas as pd


@dataclass(frozen=True)
class Prices:
    """Break-even probe prices of one curve ``(m0, m2, m5)``."""

    blind_above: float
    five_below: float
    two_ever_optimal: bool


def break_even(m0: float, m2: float, m5: float) -> Prices:
    """The two break-even prices of a three-point curve (see the module docstring)."""
    if (m0 - m2) / 2 < (m2 - m5) / 3:  # not convex: 2 probes are dominated by 0 or 5 at every price
        price = max((m0 - m5) / 5, 0.0)
        return Prices(price, price, False)
    blind = max((m0 - m2) / 2, (m0 - m5) / 5, 0.0)
    five = max(min((m2 - m5) / 3, (m0 - m5) / 5), 0.0)
    return Prices(blind, five, five < blind)


def best_budget(m0: float, m2: float, m5: float, price: float) -> int:
    """The budget minimizing ``J = miss + price k`` (ties to the smaller budget)."""
    costs = {0: m0, 2: m2 + 2 * price, 5: m5 + 5 * price}
    return min(costs, key=lambda k: (costs[k], k))


def pricing_table(curves: pd.DataFrame) -> pd.DataFrame:
    """Break-even prices per family from a breadth curve table (``family, method, k, mean``)."""
    rows = []
    for family, c in curves.groupby("family", sort=False):
        def miss(method: str, k: int) -> float:
            hit = c[(c["method"] == method) & (c["k"] == k)]["mean"]
            return float(hit.iloc[0]) if len(hit) else float("nan")

        m0, m2, m5 = miss("blind_robust", 0), miss("probe_robust", 2), miss("probe_robust", 5)
        if np.isnan([m0, m2, m5]).any():
            continue
        p = break_even(m0, m2, m5)
        rows.append({"family": family, "miss_0": m0, "miss_2": m2, "miss_5": m5, "blind_above": p.blind_above,
                     "five_below": p.five_below, "two_ever_optimal": p.two_ever_optimal})
    return pd.DataFrame(rows)


def _paper_prices() -> dict[str, tuple[float, float]]:
    """The paper's prices (Sec. III) in the family's miss units (cm -> m; the hinge in rad)."""
    from probecommit.studies.paper_values import value

    scale = {"hinge": 1.0}
    return {f: tuple(value(f"T01-pricing.{kind}.{f}") * scale.get(f, 0.01) for kind in ("blind_above", "five_below"))
            for f in ("darts", "push2d", "hinge", "push1d")}


#: The paper's prices (same units as the family's miss): blind above, five below.
PAPER_PRICES = _paper_prices()


def pricing_markdown(table: pd.DataFrame) -> str:
    head = ("| family | miss(0) | miss(2) | miss(5) | blind above (ours) | five below (ours) | two ever optimal | "
            "paper: blind above | paper: five below |\n|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for _, r in table.iterrows():
        paper = PAPER_PRICES.get(r["family"], (None, None))
        fmt = lambda v: "--" if v is None else f"{v:.4f}"  # noqa: E731
        lines.append(f"| {r['family']} | {r['miss_0']:.3f} | {r['miss_2']:.3f} | {r['miss_5']:.3f} | "
                     f"{r['blind_above']:.4f} | {r['five_below']:.4f} | {'yes' if r['two_ever_optimal'] else 'no'} | "
                     f"{fmt(paper[0])} | {fmt(paper[1])} |")
    return head + "\n".join(lines) + "\n"
