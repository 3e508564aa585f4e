"""The execution margin gamma (paper Sec. IV, "The margin").

The executor scores each aim with the capture window shrunk to ``gamma * w(c)``.
``gamma`` is searched over ``{1.00, 0.98, ..., 0.30}`` and set to the LARGEST value
whose mean predicted failure over all calibration episodes and budgets is at least
the mean realized failure of the aim it selects. That margin is validation-tuned,
not distribution-free; the distribution-free alternative is the conformal
``1 - alpha`` quantile of each calibration instance's worst-budget optimism
``max_k e_{i,k}`` with ``e_{i,k}`` the mean over repeats of realized - predicted.

Re-executing the commit for each gamma is the caller's business: the search takes
a callable ``evaluate(gamma) -> episodes`` so it needs no runner.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np
import pandas as pd

from probecommit.audit.conformal import DEFAULT_ALPHA, conformal_quantile
from probecommit.audit.io import ok_episodes

#: {1.00, 0.98, ..., 0.30}: built from integers and rounded, so 0.3 is exactly
#: the float 0.3 (np.arange(1.0, 0.29, -0.02) drifts to 0.30000000000000027).
GAMMA_GRID: np.ndarray = np.round(np.arange(100, 29, -2) / 100.0, 2)

# Mean predicted and mean realized are compared as sums over the same episodes;
# this absolute slack on the sums absorbs float round-off of equal totals.
_SUM_SLACK = 1e-9


@dataclass
class MarginResult:
    """Outcome of the margin search.

    Attributes:
        gamma: The selected margin.
        satisfied: False when no grid value satisfied the rule (gamma is then
            the smallest grid value, the most conservative one tried).
        search: One row per evaluated gamma: ``gamma``, ``n_episodes``,
            ``mean_predicted``, ``mean_realized``, ``satisfied``.
    """

    gamma: float
    satisfied: bool
    search: pd.DataFrame = field(repr=False)


def margin_satisfied(episodes: pd.DataFrame, budgets: Iterable[int] | None = None) -> tuple[bool, int, float, float]:
    """Does a table's mean predicted failure reach its mean realized failure?

    Returns:
        ``(satisfied, n_episodes, mean_predicted, mean_realized)`` over all ok
        episodes (and budgets in ``budgets`` when given).
    """
    df = ok_episodes(episodes)
    if budgets is not None:
        df = df.loc[df["k"].isin(list(budgets))]
    if len(df) == 0:
        raise ValueError("margin search: evaluate() returned no ok episodes")
    pred = df["predicted"].to_numpy(float)
    real = df["realized"].to_numpy(float)
    if not (np.isfinite(pred).all() and np.isfinite(real).all()):
        raise ValueError("margin search: predicted/realized contain NaN on ok episodes")
    ok = bool(pred.sum() >= real.sum() - _SUM_SLACK)
    return ok, len(df), float(pred.mean()), float(real.mean())


def margin_candidates(grid: Iterable[float]) -> list[float]:
    """The distinct grid values (rounded to 10 decimals) in the order the search scans them, largest first."""
    return sorted({float(g) for g in np.round(np.asarray(list(grid), dtype=float), 10)}, reverse=True)


def select_margin(evaluate: Callable[[float], pd.DataFrame], grid: Iterable[float] = GAMMA_GRID, *,
                  budgets: Iterable[int] | None = None, exhaustive: bool = False) -> MarginResult:
    """Largest gamma on the grid whose calibration episodes are not optimistic on average.

    The grid is scanned from the largest value down and the first value that
    satisfies the rule is the largest one that does, whether or not the rule is
    monotone in gamma; so the scan stops there unless ``exhaustive``.

    Args:
        evaluate: ``evaluate(gamma)`` re-executes the commit on the calibration
            instances with margin ``gamma`` and returns their episode table.
        grid: Candidate margins (default :data:`GAMMA_GRID`).
        budgets: Restrict the averages to these budgets (default: all in the table).
        exhaustive: Evaluate every grid value (for reporting the whole curve).

    Returns:
        The selected margin and the search table.
    """
    values = margin_candidates(grid)
    if not values:
        raise ValueError("margin grid is empty")
    rows = []
    chosen = None
    for gamma in values:
        ok, n, mp, mr = margin_satisfied(evaluate(gamma), budgets)
        rows.append({"gamma": gamma, "n_episodes": n, "mean_predicted": mp, "mean_realized": mr, "satisfied": ok})
        if ok and chosen is None:
            chosen = gamma
            if not exhaustive:
                break
    search = pd.DataFrame(rows)
    if chosen is None:
        warnings.warn(f"no margin on the grid makes the calibration episodes non-optimistic; "
                      f"using the smallest, {values[-1]:.2f}", RuntimeWarning, stacklevel=2)
        return MarginResult(values[-1], False, search)
    return MarginResult(chosen, True, search)


def instance_optimism(episodes: pd.DataFrame, budgets: Iterable[int] | None = None) -> pd.DataFrame:
    """``e_{i,k}``: mean over repeats of realized - predicted, instances x budgets."""
    df = ok_episodes(episodes)
    if budgets is not None:
        df = df.loc[df["k"].isin(list(budgets))]
    diff = df.assign(_e=df["realized"].astype(float) - df["predicted"].astype(float))
    return diff.pivot_table(index="instance_id", columns="k", values="_e", aggfunc="mean")


def distribution_free_margin(episodes: pd.DataFrame, alpha: float = DEFAULT_ALPHA,
                             budgets: Iterable[int] | None = None) -> float:
    """Conformal ``1 - alpha`` quantile of each instance's worst-budget optimism ``max_k e_{i,k}``.

    It is an additive allowance on the failure score: a fresh instance's
    worst-budget optimism is at most this value with probability ``>= 1 - alpha``.

    Args:
        episodes: Calibration episode table (one method and variant).
        alpha: Miscoverage level.
        budgets: Budgets over which the worst case is taken (all when None).

    Returns:
        The quantile (``+inf`` when the calibration set is too small).
    """
    return optimism_margin(instance_optimism(episodes, budgets), alpha)


def optimism_margin(optimism: pd.DataFrame, alpha: float = DEFAULT_ALPHA) -> float:
    """:func:`distribution_free_margin` from ``instance_optimism(episodes, budgets)`` (of a table,
    or of its parts of whole instances, concatenated)."""
    worst = optimism.max(axis=1, skipna=True).dropna()
    return conformal_quantile(worst.to_numpy(), alpha)
