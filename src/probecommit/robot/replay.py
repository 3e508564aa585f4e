"""Replay a session log's recorded probes under another model: as deployed, or with an injected fault.

Probes came from the frozen schedule, never from the belief, so a log replays under any
observation model or prior: each episode's belief is rebuilt from its recorded readings
with the same per-episode generator the session used (the one code path of
:func:`probecommit.robot.session.episode_belief`), and Probe-Robust commits again.
Replayed as deployed, a log reproduces its own recorded decisions exactly.

A fault sweep (paper Fig. 7c, 7d) replays the log at each fault size and reports, paired
over positions, the faulted model's optimism and coverage minus the deployed replay's,
with a cluster-bootstrap interval; a point is *resolved* when its interval excludes zero.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd

from probecommit.audit.stats import DEFAULT_RESAMPLES, DEFAULT_SEED, cluster_bootstrap_mean
from probecommit.robot.log import SessionLogError
from probecommit.robot.session import decide_belief, episode_belief, load_session
from probecommit.robot.table import SessionEpisodes, rows_from_decisions
from probecommit.runner.build import build_filter, build_model
from probecommit.runner.config import StudyConfig, config_data, parse_config
from probecommit.errors import UsageError

#: Faults a log can be replayed under.
FAULTS = ("boundary", "prior")


def with_overrides(config: StudyConfig, overrides: dict[str, dict[str, Any]]) -> StudyConfig:
    """The config with some sections changed (``model`` and ``belief`` only: the readings are fixed)."""
    bad = set(overrides) - {"model", "belief"}
    if bad:
        raise UsageError(f"a replay of recorded probes can change only the model and belief, not {sorted(bad)}")
    data = config_data(config)
    for section, values in overrides.items():
        data[section] = {**data[section], **values}
    return parse_config(data)


def fault_overrides(config: StudyConfig, fault: str, size: float) -> dict[str, dict[str, Any]]:
    """Config overrides of a fault of ``size`` mm.

    ``boundary``: the through-the-opening boundary pulled inward by ``size``
    (``model.boundary_pull_in``). ``prior``: the prior on the decision coordinate
    narrowed to ``+-size`` about zero (other latents unchanged).
    """
    if fault == "boundary":
        if "boundary_pull_in" not in type(config.model).model_fields:
            raise UsageError(f"the boundary fault needs a model with boundary_pull_in (the rig family), "
                             f"not {config.family!r}")
        return {"model": {"boundary_pull_in": float(size)}}
    if fault == "prior":
        if not size > 0:
            raise UsageError(f"the prior half-width must be > 0, got {size!r}")
        low, high = list(config.model.prior_low), list(config.model.prior_high)
        low[0], high[0] = -float(size), float(size)
        return {"model": {"prior_low": low, "prior_high": high}}
    raise UsageError(f"unknown fault {fault!r}; faults: {', '.join(FAULTS)}")


#: Fields a reproduced decision must match: the action, its predicted score and the retained set.
COMPARED = ("action", "action_index", "predicted", "retained_lo", "retained_hi", "hull_lo", "hull_hi")


def same_decision(replayed: dict[str, Any], recorded: dict[str, Any], tol: float = 1e-9) -> bool:
    """Whether a replayed decision reproduces the recorded one: the action, the predicted score and the
    retained interval and hull (an action alone can agree while the belief behind it does not)."""
    for name in COMPARED:
        a, b = np.asarray(replayed.get(name), dtype=float), np.asarray(recorded.get(name), dtype=float)
        if a.shape != b.shape or not np.all(np.isfinite(a)) or not np.all(np.abs(a - b) <= tol * (1 + np.abs(b))):
            return False
    return True


def replay_session(path: str | Path, overrides: dict[str, dict[str, Any]] | None = None,
                   variant: str | None = None) -> tuple[SessionEpisodes, float]:
    """Re-decide every committed episode of a log under ``overrides``.

    Returns:
        The audit rows of the replay, and the fraction of episodes whose decision (action,
        predicted score, retained interval and hull: :func:`same_decision`) equals the
        recorded one (1.0 for a replay as deployed).
    """
    config, episodes, truths, log = load_session(path)
    replay_config = with_overrides(config, overrides or {})
    model = build_model(replay_config)
    pfilter = build_filter(model, replay_config.belief)
    decisions, same = {}, []
    for number, ep in sorted(episodes.items()):
        if ep.decision is None:
            continue
        state, _ = episode_belief(pfilter, replay_config, number, ep.probes, ep.readings)
        decisions[number] = decide_belief(model, replay_config, state, ep.context)
        same.append(same_decision(decisions[number], ep.decision))
    # Realized outcomes are always scored by the deployed model's window at the truth.
    result = rows_from_decisions(build_model(config), episodes, truths, decisions,
                                 variant=variant or model.variant)
    result.path = log
    if result.rows.empty:
        raise SessionLogError(f"{log}: no episode can be replayed ({'; '.join(result.notes) or 'no episodes'})")
    return result, float(np.mean(same)) if same else float("nan")


def parse_sweep(text: str) -> list[float]:
    """``"0:14:1"`` -> ``[0, 1, ..., 14]`` (inclusive stop), or a comma list ``"0,4,8"``.

    Raises:
        ValueError: naming the malformed part.
    """
    text = text.strip()
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3 or not all(np.isfinite(parts)) or parts[2] <= 0 or parts[1] < parts[0]:
                raise ValueError
            n = int(np.floor((parts[1] - parts[0]) / parts[2] + 1e-9)) + 1
            if n > 1000:
                raise ValueError
            return [round(parts[0] + i * parts[2], 10) for i in range(n)]
        values = [float(p) for p in text.split(",") if p.strip()]
    except ValueError:
        raise UsageError(f"--sweep must be START:STOP:STEP (finite, STEP > 0, STOP >= START, at most 1000 points) or a comma "
                         f"list, got {text!r}") from None
    if not values or not all(np.isfinite(values)):
        raise UsageError(f"--sweep has no finite values: {text!r}")
    return values


#: The replay columns a sweep row is computed from (:func:`sweep_row`), stored per size by a publication.
SWEEP_COLUMNS = ("episode", "instance_id", "predicted", "realized", "covered", "escaped")


def fault_sweep(path: str | Path, fault: str, sizes: Iterable[float], *, resamples: int = DEFAULT_RESAMPLES,
                seed: int = DEFAULT_SEED, progress: Any = None,
                record: list[pd.DataFrame] | None = None) -> tuple[pd.DataFrame, float]:
    """Replay a log at each fault size; paired differences against the deployed replay.

    Args:
        record: A list the deployed replay's rows (``size`` NaN) and each faulted replay's rows
            (:data:`SWEEP_COLUMNS`, with ``fault`` and ``size``) are appended to, for a publication
            to store and verify to compute the rows again from (:func:`sweep_rows`).

    Returns:
        One row per size (``size``, the faulted ``coverage``, ``escape``, ``optimism``,
        and ``delta_optimism``/``delta_coverage`` with their intervals and ``resolved`` flags),
        and the deployed replay's reproduction fraction.
    """
    config, *_ = load_session(path)
    base, reproduced = replay_session(path)
    kept = [base.rows[list(SWEEP_COLUMNS)].assign(fault=fault, size=float("nan"))]
    for size in list(sizes):
        faulted, _ = replay_session(path, fault_overrides(config, fault, size), variant=f"{fault}={size:g}")
        kept.append(faulted.rows[list(SWEEP_COLUMNS)].assign(fault=fault, size=float(size)))
        if progress is not None:
            progress(size)
    stored = pd.concat(kept, ignore_index=True)
    if record is not None:
        record.append(stored)
    return sweep_rows(stored, resamples=resamples, seed=seed), reproduced


def sweep_rows(stored: pd.DataFrame, *, resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED) -> pd.DataFrame:
    """A sweep's table from its replays' rows (the deployed replay's ``size`` is NaN), in the order stored:
    one function for :func:`fault_sweep` and ``probecommit verify``."""
    base = stored[stored["size"].isna()]
    b = base.set_index("episode")
    out = []
    for (fault, size), faulted in stored[stored["size"].notna()].groupby(["fault", "size"], sort=False):
        f = faulted.set_index("episode").loc[b.index]
        clusters = b["instance_id"].to_numpy()
        d_opt = (f["realized"] - f["predicted"]) - (b["realized"] - b["predicted"])
        d_cov = f["covered"].astype(float) - b["covered"].astype(float)
        opt = cluster_bootstrap_mean(d_opt.to_numpy(), clusters, resamples=resamples, seed=seed)
        cov = cluster_bootstrap_mean(d_cov.to_numpy(), clusters, resamples=resamples, seed=seed)
        out.append({
            "fault": fault, "size": float(size), "episodes": len(f),
            "coverage": float(f["covered"].mean()), "escape": float(f["escaped"].mean()),
            "optimism": float((f["realized"] - f["predicted"]).mean()), "failure": float(f["realized"].mean()),
            "delta_optimism": opt.estimate, "delta_optimism_lo": opt.lo, "delta_optimism_hi": opt.hi,
            "optimism_resolved": bool(opt.lo > 0 or opt.hi < 0),
            "delta_coverage": cov.estimate, "delta_coverage_lo": cov.lo, "delta_coverage_hi": cov.hi,
            "coverage_resolved": bool(cov.lo > 0 or cov.hi < 0),
        })
    return pd.DataFrame(out)
