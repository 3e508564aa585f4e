"""Batched particle belief: log-space reweighting, ESS, systematic resampling, jitter.

Everything is batched over episodes: particles are ``[E, N, d]`` and log-weights
``[E, N]``. Randomness is per episode (one ``numpy.random.Generator`` each), so an
episode's result never depends on which other episodes share its batch.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Callable, Protocol, Sequence

import numpy as np

from probecommit.core.likelihood import GaussianLikelihood, Likelihood


class ForwardModel(Protocol):
    """What the filter needs from a task model."""

    prior_low: np.ndarray
    prior_high: np.ndarray
    jitter_scale: np.ndarray
    #: The few distinct noise-free readings ``predict`` can return, or None (``TaskModelBase``'s
    #: default): with levels, the filter calls ``add_reading_log_likelihood(u, particles,
    #: log_weights, level_log_likelihood[E, L])`` instead of ``predict`` under an arithmetic likelihood.
    reading_levels: tuple[float, ...] | None

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted observation ``[E, N, m]`` for probes ``u[E]`` and particles ``[E, N, d]``."""


def normalize_log_weights(log_weights: np.ndarray) -> np.ndarray:
    """Return log-weights shifted so each row's weights sum to one.

    Rows whose weights are all ``-inf`` (every particle impossible) are reset to
    uniform, which is the only belief consistent with "no information left".
    """
    return _normalize(np.asarray(log_weights, dtype=float))[0]


def _normalize(log_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`normalize_log_weights` and the log normalizer ``log sum exp`` per row ``[E]``
    (``-inf`` for a row whose every weight is zero), the same bits as both computed apart."""
    row_max = np.max(log_weights, axis=-1, keepdims=True)
    dead = ~np.isfinite(row_max)
    safe_max = np.where(dead, 0.0, row_max)
    with np.errstate(divide="ignore", invalid="ignore"):  # dead rows are replaced below
        shifted = np.subtract(log_weights, safe_max)
        log_norm = safe_max + np.log(np.sum(np.exp(shifted), axis=-1, keepdims=True))
        out = np.subtract(log_weights, log_norm, out=shifted)  # the shifted values are spent: reuse their array
    if np.any(dead):
        out = np.where(dead, -np.log(log_weights.shape[-1]), out)
    return out, log_norm[:, 0]


def normalized_weights(log_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Normalize unnormalized log-weights ``[E, N]`` and take what an update needs of them.

    Returns:
        ``(log_w, log_norm, weights, ess)``: :func:`normalize_log_weights`, the log normalizer
        ``[E]`` (``-inf`` for a row whose every weight is zero), ``exp(log_w)`` and
        :func:`effective_sample_size`; ``log_weights`` may be overwritten.
    """
    log_w, log_norm = _normalize(log_weights)
    weights = np.exp(log_w)
    return log_w, log_norm, weights, effective_sample_size(weights, log_weights)  # log_weights is spent: scratch


def effective_sample_size(weights: np.ndarray, scratch: np.ndarray | None = None) -> np.ndarray:
    """Kish effective sample size ``1 / sum w^2`` of normalized weights ``[E, N] -> [E]``.

    Args:
        weights: Normalized weights.
        scratch: An array of the weights' shape and dtype to take the squares (same bits), or None.
    """
    return 1.0 / np.sum(np.square(weights, out=scratch), axis=-1)


def systematic_resample(weights: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Systematic resampling, batched over rows.

    Args:
        weights: Normalized weights ``[E, N]``.
        offsets: One uniform in ``[0, 1)`` per row ``[E]``.

    Returns:
        Parent indices ``[E, N]``, non-decreasing within each row (copies stay in
        parent order, which the retained-set tie rule relies on).
    """
    weights = np.asarray(weights, dtype=float)
    offsets = np.asarray(offsets, dtype=float)
    n_rows, n = weights.shape
    cumulative = np.cumsum(weights, axis=1)
    cumulative[:, -1] = 1.0  # guard against round-off leaving the last point unreachable
    positions = (offsets[:, None] + np.arange(n)[None, :]) / n
    idx = np.empty((n_rows, n), dtype=np.int64)
    for r in range(n_rows):
        idx[r] = np.searchsorted(cumulative[r], positions[r], side="right")
    return np.clip(idx, 0, n - 1)


def jitter_resampled(particles: np.ndarray, rows: np.ndarray, parents: np.ndarray, noise: np.ndarray,
                     scale: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """New particles ``[E, N, d]``: rows ``rows`` replaced by their resampled copies moved by
    ``scale * noise`` and clipped to ``[low, high]``; every other row unchanged.

    Args:
        particles: ``[E, N, d]`` current particles (not modified).
        rows: ``[R]`` episodes that resample; ``parents``: ``[R, N]`` their parent indices.
        noise: ``[R, N, d]`` standard normal draws (each episode's from its own generator).
        scale, low, high: ``[d]`` jitter scale and prior box.
    """
    out = particles.copy()
    new = np.take_along_axis(particles[rows], parents[:, :, None], axis=1)
    out[rows] = np.clip(new + scale * noise, low, high)
    return out


@dataclass
class BeliefState:
    """A batch of particle beliefs.

    Attributes:
        particles: ``[E, N, d]`` latent hypotheses.
        log_weights: ``[E, N]`` normalized log-weights.
        resampled: ``[E]`` whether each episode resampled at the last update.
        u_hist, y_hist: ``[E, j, p]`` and ``[E, j, m]``, the probes assimilated so far
            (what a resample-move step needs to keep the posterior invariant).
        accepted: ``[E]`` fraction of move proposals accepted at the last update (NaN
            when no move ran).
        lost: ``[E]`` whether the last probe gave every particle zero likelihood, so the
            belief was reset to uniform weights over its particles (reported, never silent).
        log_evidence: ``[E]`` log predictive density of the last probe before it was
            assimilated (what :meth:`ParticleFilter.log_predictive` returns), a by-product
            of normalizing the weights.
    """

    particles: np.ndarray
    log_weights: np.ndarray
    resampled: np.ndarray = field(default=None)  # type: ignore[assignment]
    u_hist: np.ndarray | None = None
    y_hist: np.ndarray | None = None
    accepted: np.ndarray | None = None
    lost: np.ndarray | None = None
    log_evidence: np.ndarray | None = None
    #: ``exp(log_weights)`` as the update computed it, for the decision that follows; dropped by
    #: :meth:`compact` (a trace holds a state per budget, and a third array per state costs memory).
    fresh_weights: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.resampled is None:
            self.resampled = np.zeros(self.particles.shape[0], dtype=bool)
        if self.lost is None:
            self.lost = np.zeros(self.particles.shape[0], dtype=bool)

    @property
    def weights(self) -> np.ndarray:
        """Normalized weights ``exp(log_weights)`` ``[E, N]`` (the update's own, or computed now)."""
        return np.exp(self.log_weights) if self.fresh_weights is None else self.fresh_weights

    @classmethod
    def trace_fields(cls) -> list[str]:
        """The fields a trace keeps of a state: all but :attr:`fresh_weights`."""
        return [f.name for f in fields(cls) if f.name != "fresh_weights"]

    def compact(self) -> "BeliefState":
        """The same state without :attr:`fresh_weights` (arrays shared, nothing copied)."""
        return replace(self, fresh_weights=None)

    @property
    def n_episodes(self) -> int:
        return self.particles.shape[0]

    @property
    def n_particles(self) -> int:
        return self.particles.shape[1]

    def copy(self) -> "BeliefState":
        def maybe(a):
            return None if a is None else a.copy()
        return BeliefState(self.particles.copy(), self.log_weights.copy(), self.resampled.copy(), maybe(self.u_hist),
                           maybe(self.y_hist), maybe(self.accepted), maybe(self.lost), maybe(self.log_evidence))


@dataclass(frozen=True)
class FilterKernels:
    """The update's three hot steps, injected into :class:`ParticleFilter`: the NumPy definitions
    above by default; the runner injects the compiled ones (``probecommit.accel``), which agree
    with them to round-off."""

    normalized_weights: Callable[[np.ndarray], tuple[np.ndarray, ...]] = normalized_weights
    systematic_resample: Callable[[np.ndarray, np.ndarray], np.ndarray] = systematic_resample
    jitter_resampled: Callable[..., np.ndarray] = jitter_resampled


@dataclass
class ParticleFilter:
    """Bootstrap particle filter over a box prior, batched over episodes.

    Args:
        model: Forward model with ``predict``, prior box and jitter scales.
        likelihood: Observation likelihood (Gaussian, tempered, mixture, ...).
        n_particles: Particles per episode.
        resample_fraction: Resample when ESS falls below this fraction of N.
        jitter: Whether to jitter copies after resampling.
        rejuvenation: Fraction of particles redrawn from the prior at each resampling.
        move: What the jitter is. ``"jitter"`` (the paper): every copy moves by the
            jitter and is clipped to the prior box, which biases the belief (it does not
            converge to the posterior as N grows). ``"mh"``: resample-move; the jittered
            copy is a random-walk proposal accepted with the Metropolis-Hastings
            probability against the prior and the likelihood of every probe seen so
            far, so the posterior is invariant and the belief converges.
        move_steps: MH steps per resampling (``move="mh"`` only).
        kernels: The update's hot steps (:class:`FilterKernels`; NumPy's by default).
    """

    model: ForwardModel
    likelihood: Likelihood
    n_particles: int = 1024
    resample_fraction: float = 0.5
    jitter: bool = True
    rejuvenation: float = 0.0
    move: str = "jitter"
    move_steps: int = 1
    kernels: FilterKernels = field(default_factory=FilterKernels)

    def __post_init__(self) -> None:
        if self.move not in ("jitter", "mh"):
            raise ValueError(f"move must be 'jitter' or 'mh', got {self.move!r}")
        if self.move_steps < 1:
            raise ValueError(f"move_steps must be >= 1, got {self.move_steps!r}")

    @classmethod
    def gaussian(cls, model: ForwardModel, sigma: float, **kwargs) -> "ParticleFilter":
        return cls(model=model, likelihood=GaussianLikelihood(sigma), **kwargs)

    def initial(self, rngs: Sequence[np.random.Generator]) -> BeliefState:
        """Draw ``N`` prior particles per episode from the box prior."""
        low = np.asarray(self.model.prior_low, dtype=float)
        high = np.asarray(self.model.prior_high, dtype=float)
        d = low.shape[0]
        particles = np.empty((len(rngs), self.n_particles, d))
        for rng, row in zip(rngs, particles):  # each episode's draws written in place: no stack copy
            rng.random(out=row)
        particles *= high - low
        particles += low
        log_w = np.full((len(rngs), self.n_particles), -np.log(self.n_particles))
        return BeliefState(particles, log_w)

    def log_predictive(self, state: BeliefState, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Log predictive density of ``y`` before it is assimilated, per episode ``[E]``."""
        pred = self.model.predict(np.asarray(u), state.particles)
        loglik = self.likelihood.log_likelihood(np.asarray(y, dtype=float), pred)
        a = state.log_weights + loglik
        m = np.max(a, axis=1)
        safe = np.where(np.isfinite(m), m, 0.0)
        return safe + np.log(np.sum(np.exp(a - safe[:, None]), axis=1))

    def update(
        self, state: BeliefState, u: np.ndarray, y: np.ndarray, rngs: Sequence[np.random.Generator]
    ) -> BeliefState:
        """Assimilate one probe per episode, resampling where ESS < fraction * N.

        Args:
            state: Current beliefs (not modified).
            u: Probe per episode ``[E]`` (or ``[E, p]``).
            y: Observation per episode ``[E, m]``.
            rngs: One generator per episode; only resampling episodes draw from it.
        """
        n_e = state.n_episodes
        u = np.asarray(u, dtype=float)
        y = np.asarray(y, dtype=float)
        unnormalized = self._reweighted(state, u, y)
        log_w, log_evidence, weights, ess = self.kernels.normalized_weights(unnormalized)
        lost = ~np.isfinite(log_evidence)
        u_now, y_now = u.reshape(n_e, 1, -1), y.reshape(n_e, 1, -1)
        u_hist = u_now if state.u_hist is None else np.concatenate([state.u_hist, u_now], axis=1)
        y_hist = y_now if state.y_hist is None else np.concatenate([state.y_hist, y_now], axis=1)
        particles = state.particles  # copied below only if some episode resamples
        resample = ess < self.resample_fraction * self.n_particles
        accepted = np.full(n_e, np.nan)
        if np.any(resample):
            rows = np.flatnonzero(resample)
            offsets = np.array([rngs[r].random() for r in rows])
            parents = self.kernels.systematic_resample(weights[rows], offsets)
            low = np.asarray(self.model.prior_low, dtype=float)
            high = np.asarray(self.model.prior_high, dtype=float)
            scale = np.asarray(self.model.jitter_scale, dtype=float)
            if self.jitter and self.move == "jitter" and self.rejuvenation == 0:  # the paper's filter, one pass
                noise = np.empty((len(rows), *particles.shape[1:]))
                for r, row in zip(rows, noise):  # in place: the same draws as standard_normal(shape), no stack copy
                    rngs[r].standard_normal(out=row)
                particles = self.kernels.jitter_resampled(particles, rows, parents, noise, scale, low, high)
            else:
                particles = particles.copy()
                particles[rows], accepted[rows] = self._move(particles[rows], parents, u_hist[rows], y_hist[rows],
                                                             [rngs[r] for r in rows], low, high, scale)
            log_w[rows] = -np.log(self.n_particles)
            # Every resampled weight is exp(-log N): one row of NumPy's exp gives each its bits
            # (its lanes are independent), not one exp per resampled particle.
            weights[rows] = np.exp(log_w[rows[0]])
        return BeliefState(particles, log_w, resample, u_hist, y_hist, accepted, lost, log_evidence, weights)

    def _reweighted(self, state: BeliefState, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Unnormalized log-weights ``log_weights + log p(y | u, theta)`` ``[E, N]``.

        A model whose readings take a few levels (``reading_levels``) under an arithmetic
        likelihood has one log-likelihood per level and episode: the model picks each
        particle's (``add_reading_log_likelihood``); the same bits as predicting every particle.
        """
        levels = self.model.reading_levels
        if levels is not None and getattr(self.likelihood, "arithmetic", False) and y.shape[-1] == 1:
            level_pred = np.empty((state.n_episodes, len(levels), 1))
            level_pred[:, :, 0] = levels
            level_ll = self.likelihood.log_likelihood(y.reshape(-1, 1), level_pred)
            return self.model.add_reading_log_likelihood(u, state.particles, state.log_weights, level_ll)
        loglik = self.likelihood.log_likelihood(y, self.model.predict(u, state.particles))
        return state.log_weights + loglik

    def _move(self, particles, parents, u_hist, y_hist, rngs, low, high, scale):
        """Resampled copies of ``particles`` (the resampling rows) after the configured move:
        MH, jitter, rejuvenation from the prior, then clipped to the box.

        Returns:
            The new particles and the MH acceptance rate per row (NaN without MH).
        """
        new = np.take_along_axis(particles, parents[:, :, None], axis=1)
        accepted = np.full(len(rngs), np.nan)
        if self.jitter and self.move == "mh":
            new, accepted = self._mh_move(new, u_hist, y_hist, rngs, low, high, scale)
        for i, rng in enumerate(rngs):
            if self.jitter and self.move == "jitter":
                new[i] = new[i] + scale * rng.standard_normal(new[i].shape)
            if self.rejuvenation > 0:
                n_fresh = int(round(self.rejuvenation * self.n_particles))
                if n_fresh:
                    which = rng.choice(self.n_particles, size=n_fresh, replace=False)
                    new[i, which] = low + (high - low) * rng.random((n_fresh, low.shape[0]))
        return np.clip(new, low, high), accepted

    def history_log_likelihood(self, particles: np.ndarray, u_hist: np.ndarray, y_hist: np.ndarray) -> np.ndarray:
        """Log-likelihood ``[E, N]`` of every probe seen so far, ``sum_j log p(y_j | u_j, theta)``."""
        total = np.zeros(particles.shape[:2])
        for j in range(u_hist.shape[1]):
            total += self.likelihood.log_likelihood(y_hist[:, j], self.model.predict(u_hist[:, j], particles))
        return total

    def _mh_move(self, particles, u_hist, y_hist, rngs, low, high, scale):
        """Random-walk Metropolis-Hastings on the resampled copies; leaves the posterior invariant.

        The proposal is the paper's jitter (Gaussian, ``jitter_scale``); the target is the
        prior box times the likelihood of all probes so far. Each episode draws its
        proposals and acceptance uniforms from its own generator.

        Returns:
            The moved particles and the acceptance rate per episode.
        """
        n_rows, n, d = particles.shape
        current = particles
        current_ll = self.history_log_likelihood(current, u_hist, y_hist)
        taken = np.zeros(n_rows)
        for _ in range(self.move_steps):
            noise = np.stack([rng.standard_normal((n, d)) for rng in rngs])
            log_uniform = np.log(np.stack([rng.random(n) for rng in rngs]))
            proposal = current + scale * noise
            inside = np.all((proposal >= low) & (proposal <= high), axis=-1)
            proposal_ll = np.where(inside, self.history_log_likelihood(np.clip(proposal, low, high), u_hist, y_hist), -np.inf)
            with np.errstate(invalid="ignore"):
                ratio = proposal_ll - current_ll
            # From an impossible state any possible proposal is taken.
            accept = inside & np.where(np.isneginf(current_ll), np.isfinite(proposal_ll), log_uniform < ratio)
            current = np.where(accept[..., None], proposal, current)
            current_ll = np.where(accept, proposal_ll, current_ll)
            taken += accept.mean(axis=1)
        return current, taken / self.move_steps
