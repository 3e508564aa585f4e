"""Robust filters as an alternative to the known-fault correction.

Tempering ``p^(1/T)``, a contamination mixture ``(1 - eps) p + eps q0`` with ``q0``
uniform over the observable height range, and rejuvenation (a fraction of
particles redrawn from the prior at each resampling) are tuned on the development
instances under the deployed model (lowest failure at the final budget, ties to the
first grid value), then confronted with the boundary error on held-out probes.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from probecommit.runner.replay import CHUNK_INSTANCES, LoadedRun, replay_episodes


def robust_candidates(temperatures, epsilons, rejuvenation, mixture_range) -> dict[str, list[tuple[float, dict[str, Any]]]]:
    """Belief overrides for each filter family and grid value, in grid order."""
    lo, hi = mixture_range
    return {
        "tempering": [(t, {"likelihood": "tempered", "temperature": float(t)}) for t in temperatures],
        "mixture": [(e, {"likelihood": "mixture", "epsilon": float(e), "mixture_low": lo, "mixture_high": hi}) for e in epsilons],
        "rejuvenation": [(r, {"rejuvenation": float(r)}) for r in rejuvenation],
    }


def final_failure(episodes: pd.DataFrame) -> float:
    return float(final_rows(episodes)["realized"].mean())


def final_rows(episodes: pd.DataFrame) -> pd.DataFrame:
    """The rows :func:`final_failure` averages: ok probe-executor rows at the final budget."""
    probe = episodes[(episodes.method == "probe_robust") & (episodes.status == "ok")]
    return probe[probe.k == probe.k.max()]


def mark_chosen(table: pd.DataFrame) -> pd.DataFrame:
    """``chosen``: per family, the candidate of lowest failure; ties to the first grid value (idxmin
    returns the first minimum)."""
    winners = table.groupby("family", sort=False)["failure"].idxmin()
    return table.assign(chosen=table.index.isin(winners.values))


def tune_robust_filters(development: LoadedRun, candidates, progress=None,
                        chunk_instances: int | None = CHUNK_INSTANCES,
                        record: list[pd.DataFrame] | None = None) -> pd.DataFrame:
    """Final-budget failure of every candidate on the development run; ``chosen`` marks the winners.

    ``chunk_instances``: instances whose beliefs a replay holds at once. ``record``: a list each
    candidate's final-budget rows (:func:`final_rows`, with ``family`` and ``value``) are appended to,
    for a publication to store and verify to tune again from.
    """
    rows = []
    total = sum(len(v) for v in candidates.values())
    for family, grid in candidates.items():
        for value, belief in grid:
            episodes, _ = replay_episodes(development, {"belief": belief}, chunk_instances=chunk_instances)
            rows.append({"family": family, "value": value, "failure": final_failure(episodes), "belief": belief})
            if record is not None:
                record.append(final_rows(episodes).assign(family=family, value=value))
            if progress:
                progress(len(rows), total)
    return mark_chosen(pd.DataFrame(rows))
