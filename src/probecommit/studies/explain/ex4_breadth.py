"""Table II's rows under one prior width at a time: the single-width rule of E35..E40.

Why: the prior-width sweep (``studies/explain/breadth.py``) first asked whether each paper
cell lies inside the *span* of our intervals over the widths. That lets Blind-Bayes be
matched at one width and Probe-Robust at another, so it can "explain" a row that no single
scene produces. The stricter question (docs/decisions.md, "ex4"): is there ONE width at which
every paper cell of the row lies inside our 95 % interval at once? The keys say how many of
the row's paper cells one width holds at most, the smallest width that holds that many, and
whether that is all of them.
"""

from __future__ import annotations

from typing import Any


def single_width(rows: dict[float, dict[str, float]], paper: dict[str, float]) -> dict[str, Any]:
    """``single_width.*`` keys of one family from its rows by width (``{scale: {cell, cell_lo, cell_hi}}``)
    and the paper's cells (``paper_cells``; prices are ignored: they have no interval)."""
    cells = [name for name in paper if not name.startswith("price.")]
    inside = {s: sum(r[f"{c}_lo"] <= paper[c] <= r[f"{c}_hi"] for c in cells) for s, r in rows.items()}
    best = max(inside.values(), default=0)
    at = min((s for s, n in inside.items() if n == best), default=float("nan"))
    return {"single_width.best_cells_inside": float(best), "single_width.best_scale": float(at),
            "single_width.all_inside": float(bool(cells) and best == len(cells))}
