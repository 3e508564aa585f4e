"""A session log as audit rows, and the paper's Table IX (the run on the physical arm).

Every decided episode whose position has a recorded truth becomes one audit row
(:func:`probecommit.audit.episode_row`): realized failure is the deployed model's loss
of the committed action at the measured truth (for the rig, the aim outside the model's
window of the measured centre), coverage and escape are read off the recorded retained
interval and hull. Episodes without a truth are counted and named, never scored.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.audit.io import validate_episodes
from probecommit.audit.rows import episode_row
from probecommit.audit.stats import DEFAULT_RESAMPLES, DEFAULT_SEED, cluster_bootstrap_mean, few_clusters_note
from probecommit.robot.log import SessionLogError
from probecommit.robot.session import EpisodeRecord, load_session
from probecommit.runner.build import build_model


@dataclass
class SessionEpisodes:
    """Audit rows of a session and what could not be scored.

    Attributes:
        rows: One row per scored episode (audit columns, plus ``entered`` and ``aim_error``).
        unscored: ``{reason: [episode numbers]}`` for episodes left out (no decision, no truth).
        path: The log.
    """

    rows: pd.DataFrame
    unscored: dict[str, list[int]] = field(default_factory=dict)
    path: Path | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def notes(self) -> list[str]:
        out = list(self.warnings)
        for reason, episodes in self.unscored.items():
            shown = ", ".join(map(str, episodes[:8])) + (" ..." if len(episodes) > 8 else "")
            out.append(f"{len(episodes)} episode(s) not scored ({reason}): {shown}")
        return out


def realized_outcome(model: Any, action: Any, truth: np.ndarray, context: Any = None) -> float:
    """The deployed model's loss of ``action`` at the truth (and the episode's context), margin one
    (failure 0/1 or miss)."""
    scorer = model.with_margin(1.0)
    ctx = None if context is None else np.asarray(context, dtype=float).reshape(1, -1)
    loss = scorer.loss(np.atleast_2d(np.asarray(action, dtype=float)), np.asarray(truth, dtype=float)[None, None, :], ctx)
    return float(np.asarray(loss).reshape(-1)[0])


def rows_from_decisions(model: Any, episodes: dict[int, EpisodeRecord], truths: dict[str, list[float]],
                        decisions: dict[int, dict[str, Any]] | None = None, variant: str = "deployed") -> SessionEpisodes:
    """Audit rows of decided episodes with truths (``decisions`` overrides the recorded ones: a replay)."""
    rows, unscored = [], {}
    counter: dict[tuple[str, int], int] = {}
    for number in sorted(episodes):
        ep = episodes[number]
        decision = (decisions or {}).get(number, ep.decision)
        if decision is None:
            unscored.setdefault("never committed", []).append(number)
            continue
        truth = truths.get(ep.position)
        if truth is None:
            unscored.setdefault(f"no truth recorded for position {ep.position!r}", []).append(number)
            continue
        theta = np.asarray(truth, dtype=float)
        z_true = float(model.decision(theta[None, :])[0])
        k = len(ep.probes)
        repeat = counter.get((ep.position, k), 0)
        counter[(ep.position, k)] = repeat + 1
        action = decision["action"]
        entered = (ep.outcome or {}).get("entered")
        rows.append(episode_row(
            instance_id=ep.position, repeat=repeat, k=k, z_true=z_true, action=action,
            predicted=decision["predicted"], realized=realized_outcome(model, action, theta, ep.context),
            retained=(decision["retained_lo"], decision["retained_hi"]), hull=(decision["hull_lo"], decision["hull_hi"]),
            method="probe_robust" if k else "blind_robust", variant=variant, episode=number,
            entered=np.nan if entered is None else float(entered),
            aim_error=float(abs(np.ravel(action)[0] - z_true)), n_retained=decision.get("n_retained"),
        ))
    frame = pd.DataFrame(rows)
    if len(frame):  # the episode-row rules, as for every other audit path
        loss = "binary" if getattr(model, "binary_loss", False) else "continuous"
        frame = validate_episodes(frame, "session log", structure=False, loss=loss)
        frame.attrs = {}
    return SessionEpisodes(frame, unscored)


def session_episodes(path: str | Path) -> SessionEpisodes:
    """The audit rows of a session log as recorded.

    Raises:
        SessionLogError: the log is unreadable, or no episode can be scored (the message says why).
    """
    from probecommit.robot.log import read_records

    config, episodes, truths, log = load_session(path)
    result = rows_from_decisions(build_model(config), episodes, truths)
    result.path = log
    _, partial = read_records(log, allow_partial=True)
    if partial:
        result.warnings.append(f"the log's last line was cut off mid-write ({len(partial)} bytes; its call never "
                               "returned) and is ignored here; Session.open(..., repair=True) moves it to .partial")
    if result.rows.empty:
        why = "; ".join(result.notes) or "it has no episodes"
        raise SessionLogError(f"{log}: no episode can be audited ({why})")
    few = few_clusters_note(int(result.rows.groupby("k")["instance_id"].nunique().min()),
                            "the optimism and aim-error intervals")
    if few:
        result.warnings.append(few)
    return result


def robot_table(rows: pd.DataFrame, *, resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED) -> pd.DataFrame:
    """Table IX: by number of taps, episodes, in window, entered, predicted, realized, optimism (with a
    cluster-bootstrap interval over positions), coverage, escape and mean aim error (with its interval)."""
    out = []
    for k, g in rows.groupby("k", sort=True):
        clusters = g["instance_id"].to_numpy()
        optimism = cluster_bootstrap_mean((g["realized"] - g["predicted"]).to_numpy(), clusters,
                                          resamples=resamples, seed=seed)
        aim = cluster_bootstrap_mean(g["aim_error"].to_numpy(), clusters, resamples=resamples, seed=seed)
        entered = g["entered"].dropna()
        out.append({
            "taps": int(k), "episodes": len(g), "positions": int(g["instance_id"].nunique()),
            "in_window": int((g["realized"] == 0).sum()),
            "entered": int(entered.sum()) if len(entered) else np.nan,
            "predicted": float(g["predicted"].mean()), "realized": float(g["realized"].mean()),
            "optimism": optimism.estimate, "optimism_lo": optimism.lo, "optimism_hi": optimism.hi,
            "covered": int(g["covered"].sum()), "coverage": float(g["covered"].mean()),
            "escape": float(g["escaped"].mean()),
            "aim_error": aim.estimate, "aim_error_lo": aim.lo, "aim_error_hi": aim.hi,
        })
    return pd.DataFrame(out)
