"""Rollout, belief traces and commits: the episode pipeline.

Rollout (the simulator) and inference (the model) are separate. ``rollout`` draws
probes and readings from the simulator; ``build_trace`` recomputes beliefs from
stored probes; ``commit`` turns beliefs into actions, scores them with the model and
asks the simulator for the realized outcome. Replays under another model variant,
faults and calibration all reuse stored probes, so compared arms see identical taps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Mapping

import numpy as np
import pandas as pd

from probecommit.audit.score import coverage_score
from probecommit.core.belief import BeliefState, ParticleFilter
from probecommit.core.executors import interval_success_counts, prior_expected_loss, scenario_max_loss, select_action
from probecommit.core.retained import masked_interval, retained_mask, weighted_mean, weighted_variance
from probecommit.runner.seeding import INFERENCE, ROLLOUT, blind_rng, episode_rng

#: Number of evenly spaced scenarios added across the grown interval when t > 1.
GROWN_SET_POINTS = 9


@dataclass
class ProbeBatch:
    """Stored probes of ``E`` episodes (one trajectory each, ``K`` probes)."""

    split: str
    instance_id: np.ndarray  # [E] str
    instance_index: np.ndarray  # [E] int
    repeat: np.ndarray  # [E] int
    truths: np.ndarray  # [E, d]
    u: np.ndarray  # [E, K]
    y: np.ndarray  # [E, K, m]
    status: np.ndarray = field(default=None)  # type: ignore[assignment]  # [E] "ok" / "failed"
    error: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        n = len(self.instance_id)
        if self.status is None:
            self.status = np.full(n, "ok", dtype=object)
        if self.error is None:
            self.error = np.full(n, "", dtype=object)

    @property
    def n_episodes(self) -> int:
        return len(self.instance_id)

    def subset(self, rows: np.ndarray) -> "ProbeBatch":
        return ProbeBatch(
            self.split, self.instance_id[rows], self.instance_index[rows], self.repeat[rows],
            self.truths[rows], self.u[rows], self.y[rows], self.status[rows], self.error[rows],
        )

    def probes_frame(self) -> pd.DataFrame:
        """Long table ``instance_id, repeat, j, u, y`` of the successful episodes."""
        ok = self.status == "ok"
        e, k = self.u[ok].shape
        return pd.DataFrame(
            {
                "instance_id": np.repeat(self.instance_id[ok], k).astype(str),
                "repeat": np.repeat(self.repeat[ok], k).astype(np.int64),
                "j": np.tile(np.arange(1, k + 1), e).astype(np.int64),
                "u": self.u[ok].ravel().astype(float),
                "y": self.y[ok][..., 0].ravel().astype(float),
            }
        )


def rollout(
    instances: pd.DataFrame,
    repeats: int,
    schedule: str | list[float],
    budget: int,
    probe_grid: np.ndarray,
    simulator,
    seed: int,
    latent_names: tuple[str, ...],
) -> ProbeBatch:
    """Draw every episode's probe trajectory from the simulator.

    Random schedules draw the probe position and then the reading noise at each
    step, from the episode's own rollout stream, so a budget-``k`` trajectory is
    the prefix of any longer one with the same seed.
    """
    rows = []
    for _, inst in instances.iterrows():
        theta = np.array([inst[f"true_{n}"] for n in latent_names], dtype=float)
        for r in range(repeats):
            rng = episode_rng(seed, str(inst["split"]), int(inst["instance_index"]), r, ROLLOUT)
            u = np.empty(budget)
            y = np.full((budget, 1), np.nan)
            status, error = "ok", ""
            try:
                for j in range(budget):
                    if schedule == "random":
                        u[j] = probe_grid[rng.integers(len(probe_grid))]
                    else:
                        u[j] = schedule[j]
                    y[j] = simulator.probe(theta, u[j], rng)
                    if not np.all(np.isfinite(y[j])):
                        raise FloatingPointError(f"{simulator.engine} returned {y[j].tolist()} for probe u={u[j]}")
            except Exception as exc:  # noqa: BLE001 - one bad engine query must not end the study
                status, error = "failed", f"probe {j + 1}: {type(exc).__name__}: {exc}"
            rows.append((inst["instance_id"], int(inst["instance_index"]), r, theta, u, y, status, error))
    split = str(instances["split"].iloc[0]) if len(instances) else ""
    return ProbeBatch(
        split=split,
        instance_id=np.array([r[0] for r in rows], dtype=object),
        instance_index=np.array([r[1] for r in rows], dtype=np.int64),
        repeat=np.array([r[2] for r in rows], dtype=np.int64),
        truths=np.array([r[3] for r in rows], dtype=float).reshape(len(rows), len(latent_names)),
        u=np.array([r[4] for r in rows], dtype=float).reshape(len(rows), budget),
        y=np.array([r[5] for r in rows], dtype=float).reshape(len(rows), budget, 1),
        status=np.array([r[6] for r in rows], dtype=object),
        error=np.array([r[7] for r in rows], dtype=object),
    )


@dataclass
class BeliefTrace:
    """Beliefs of a batch of episodes after each committed budget (k = 0 is the prior)."""

    batch: ProbeBatch
    states: dict[int, BeliefState]
    surprise: np.ndarray  # [E, K] -log predictive density of probe j before assimilation

    @property
    def budgets(self) -> list[int]:
        return sorted(k for k in self.states if k > 0)


def build_trace(pfilter: ParticleFilter, batch: ProbeBatch, seed: int, budgets: Iterable[int]) -> BeliefTrace:
    """Recompute beliefs from stored probes (successful episodes of ``batch`` only)."""
    ok = np.flatnonzero(batch.status == "ok")
    batch = batch.subset(ok)
    rngs = [
        episode_rng(seed, batch.split, int(i), int(r), INFERENCE)
        for i, r in zip(batch.instance_index, batch.repeat)
    ]
    budgets = set(budgets)
    state = pfilter.initial(rngs)
    states = {0: state}
    k_max = max(budgets) if budgets else 0
    surprise = np.full((batch.n_episodes, batch.u.shape[1]), np.nan)
    for j in range(1, k_max + 1):
        u_j, y_j = batch.u[:, j - 1], batch.y[:, j - 1]
        surprise[:, j - 1] = -pfilter.log_predictive(state, u_j, y_j)
        state = pfilter.update(state, u_j, y_j, rngs)
        if j in budgets:
            states[j] = state
    return BeliefTrace(batch, states, surprise)


def grown_scenarios(particles: np.ndarray, threshold: float, domain_width: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The set for a threshold ``t > 1``: the hull grown by ``(t - 1) D`` on each side.

    It is represented by all ``N`` particles plus nine points evenly spaced across the
    grown interval, each at the particles' median of the other latents (the clearance
    scale for insertion). The decision coordinate is latent 0.

    Returns:
        Scenarios ``[E, N + 9, d]`` and the grown interval ``(lo, hi)`` per episode.
    """
    z = particles[..., 0]
    grow = (threshold - 1.0) * domain_width
    lo, hi = z.min(axis=1) - grow, z.max(axis=1) + grow
    extra = np.repeat(np.median(particles, axis=1)[:, None, :], GROWN_SET_POINTS, axis=1)
    extra[..., 0] = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, GROWN_SET_POINTS)[None, :]
    return np.concatenate([particles, extra], axis=1), lo, hi


def _choose(model, scenarios: np.ndarray, mask: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Scenario executor: action index and its score per episode."""
    if model.binary_loss:
        kept = np.maximum(mask.sum(axis=-1), 1)
        # Integer counting keeps scores exact and independent of batch shape.
        if hasattr(model, "success_interval"):
            lo, hi = model.success_interval(scenarios)
            failures = mask.sum(axis=-1)[:, None] - interval_success_counts(lo, hi, mask, model.action_grid)
        else:
            failures = np.sum(model.loss(model.action_grid, scenarios) & mask[:, None, :], axis=-1)
        scores = failures / kept[:, None]
    else:
        scores = scenario_max_loss(model.loss(model.action_grid, scenarios), mask)
    idx = select_action(scores, model.action_grid, reference)
    return idx, np.take_along_axis(scores, idx[:, None], axis=1)[:, 0]


def blind_bayes_action(model, seed: int, n_samples: int) -> tuple[float, float]:
    """Blind-Bayes: the prior-expected-loss optimum over a large fixed prior sample.

    Returns:
        The action and its prior expected loss.
    """
    rng = blind_rng(seed)
    low, high = np.asarray(model.prior_low, float), np.asarray(model.prior_high, float)
    sample = low + (high - low) * rng.random((n_samples, low.shape[0]))
    expected = prior_expected_loss(model.loss(model.action_grid, sample))
    ref = np.array([float(np.mean(model.decision(sample)))])
    idx = int(select_action(expected[None, :], model.action_grid, ref)[0])
    return float(model.action_grid[idx]), float(expected[idx])


def commit(
    trace: BeliefTrace,
    model,
    simulator,
    thresholds: float | Mapping[int, float] = 0.8,
    margin: float | None = None,
    methods: Iterable[str] = ("probe_robust",),
    blind: tuple[float, float] | None = None,
) -> pd.DataFrame:
    """Commit once per episode and budget, and score the commit against ground truth.

    Args:
        trace: Beliefs per budget.
        model: The model scoring actions (its variant labels the rows).
        simulator: Ground truth; ``execute`` is cached per distinct aim.
        thresholds: Retained mass ``nu`` (or conformal threshold ``t``), a float for
            every budget or ``{k: t}``; ``t > 1`` uses the grown set.
        margin: Capture-window shrink ``gamma`` (None keeps the model's).
        methods: Any of ``probe_robust`` (k >= 1), ``blind_robust`` and
            ``blind_bayes`` (k = 0).
        blind: ``(action, expected loss)`` of Blind-Bayes, required for that method.

    Returns:
        The episode table (columns of ``store.schema.EPISODE_COLUMNS``).
    """
    if margin is not None:
        model = model.with_margin(margin)
    methods = list(methods)
    batch = trace.batch
    frames = []
    plan: list[tuple[str, int]] = []
    if "blind_bayes" in methods:
        plan.append(("blind_bayes", 0))
    if "blind_robust" in methods:
        plan.append(("blind_robust", 0))
    if "probe_robust" in methods:
        # Per-budget thresholds commit only at the budgets they name.
        budgets = [k for k in trace.budgets if not isinstance(thresholds, Mapping) or k in thresholds]
        plan += [("probe_robust", k) for k in budgets]
    z_true = model.decision(batch.truths)
    for plan_index, (method, k) in enumerate(plan):
        state = trace.states[k]
        weights, particles = state.weights, state.particles
        z = model.decision(particles)
        t = float(thresholds[k] if isinstance(thresholds, Mapping) else thresholds)
        if method == "blind_bayes":
            if blind is None:
                raise ValueError("blind_bayes needs the blind action")
            mask = np.ones_like(weights, dtype=bool)
            lo, hi = masked_interval(z, mask)
            action = np.full(batch.n_episodes, blind[0])
            predicted = np.full(batch.n_episodes, blind[1])
        else:
            if t <= 1:
                mask = retained_mask(weights, t)
                lo, hi = masked_interval(z, mask)
                scen, smask = particles, mask
                ref = weighted_mean(z, weights, mask)
            else:
                scen, lo, hi = grown_scenarios(particles, t, model.decision_domain_width)
                smask = np.ones(scen.shape[:2], dtype=bool)
                mask = np.ones_like(weights, dtype=bool)
                ref = weighted_mean(z, weights)
            idx, predicted = _choose(model, scen, smask, ref)
            action = model.action_grid[idx]
        hull_lo, hull_hi = z.min(axis=1), z.max(axis=1)
        realized = np.full(batch.n_episodes, np.nan)
        status = np.full(batch.n_episodes, "ok", dtype=object)
        error = np.full(batch.n_episodes, "", dtype=object)
        for e in range(batch.n_episodes):
            try:
                realized[e] = simulator.execute(batch.truths[e], float(action[e]))["realized"]
            except Exception as exc:  # noqa: BLE001 - mark the episode, keep the study going
                status[e], error[e] = "failed", f"execute: {type(exc).__name__}: {exc}"
        surprise = trace.surprise[:, :k]
        frames.append(
            pd.DataFrame(
                {
                    "instance_id": batch.instance_id.astype(str),
                    "repeat": batch.repeat.astype(np.int64),
                    "k": np.int64(k),
                    "method": method,
                    "variant": model.variant,
                    "action": action.astype(float),
                    "predicted": predicted.astype(float),
                    "realized": realized,
                    "z_true": z_true,
                    "retained_lo": lo,
                    "retained_hi": hi,
                    "hull_lo": hull_lo,
                    "hull_hi": hull_hi,
                    "covered": (lo <= z_true) & (z_true <= hi),
                    "escaped": (z_true < hull_lo) | (z_true > hull_hi),
                    "score_s": coverage_score(z, weights, z_true, model.decision_domain_width),
                    "post_var": weighted_variance(z, weights),
                    "max_surprise": surprise.max(axis=1) if k > 0 else np.full(batch.n_episodes, np.nan),
                    "n_retained": mask.sum(axis=1).astype(np.int64),
                    "status": status,
                    "error": error,
                    "_row": np.arange(batch.n_episodes),
                    "_plan": plan_index,
                }
            )
        )
    if not frames:
        return pd.DataFrame()
    # Canonical order: episode by episode, each in plan order (blind first, then budgets).
    table = pd.concat(frames, ignore_index=True).sort_values(["_row", "_plan"], kind="stable")
    return table.drop(columns=["_row", "_plan"]).reset_index(drop=True)


def failed_episode_rows(batch: ProbeBatch, variant: str) -> pd.DataFrame:
    """Episode rows for trajectories whose rollout failed (kept, counted, never scored)."""
    bad = np.flatnonzero(batch.status != "ok")
    return pd.DataFrame(
        {
            "instance_id": batch.instance_id[bad].astype(str),
            "repeat": batch.repeat[bad].astype(np.int64),
            "k": np.int64(0),
            "method": "rollout",
            "variant": variant,
            "status": "failed",
            "error": batch.error[bad].astype(str),
        }
    )
