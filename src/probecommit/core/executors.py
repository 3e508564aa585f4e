"""Executors: Blind-Bayes, Blind-Robust and Probe-Robust(k), as objects over a model.

An executor takes a task model (``tasks.base.TaskModel``) and a belief and returns,
per episode, the committed action's grid index, its modeled score and the retained
set it scored. Binary loss: the unweighted scenario failure fraction over the
retained set; continuous loss: scenario minimax (the largest miss over it).

Tie-break rule (every executor, documented in docs/decisions.md): among actions
whose score equals the minimum (within ``SCORE_TIE_TOLERANCE``), choose the one with
the lowest ``model.tie_break_cost`` against a *reference* computed from the belief
alone (the weighted mean of the scenarios scored); if still tied, the lowest action
index. The truth is never used.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable, Protocol, Sequence, runtime_checkable

import numpy as np

from probecommit.core.retained import belief_reference, masked_interval, retained_summary

SCORE_TIE_TOLERANCE = 1e-12
#: Number of evenly spaced scenarios added across the grown interval when t > 1.
GROWN_SET_POINTS = 9


def select_action(scores: np.ndarray, tie_cost: np.ndarray) -> np.ndarray:
    """Index of the best action per episode under the documented tie-break.

    Args:
        scores: ``[E, A]`` lower is better.
        tie_cost: ``[E, A]`` secondary cost among tied actions (the model's
            ``tie_break_cost`` against the belief's reference).

    Returns:
        ``[E]`` integer indices into the action grid.
    """
    scores = np.asarray(scores, dtype=float)
    best = np.min(scores, axis=1, keepdims=True)
    tied = scores <= best + SCORE_TIE_TOLERANCE
    cost = np.where(tied, np.asarray(tie_cost, dtype=float), np.inf)
    # argmin returns the first (lowest-index) minimum, which is the final tie-break.
    return np.argmin(cost, axis=1)


def scenario_failure_fraction(failures: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Unweighted fraction of retained scenarios that fail, per action.

    Args:
        failures: ``[E, A, N]`` boolean failure of action ``a`` under particle ``n``.
        mask: ``[E, N]`` retained scenarios.

    Returns:
        ``[E, A]`` failure fraction.
    """
    kept = np.maximum(np.sum(mask, axis=-1), 1)
    return np.einsum("ean,en->ea", failures.astype(np.float64), mask.astype(np.float64)) / kept[:, None]


def interval_success_counts(lo: np.ndarray, hi: np.ndarray, mask: np.ndarray, actions: np.ndarray) -> np.ndarray:
    """Retained scenarios whose open success interval ``(lo, hi)`` contains each action.

    An ``O(E (N + A))`` alternative to materializing ``[E, A, N]`` failures, for
    tasks whose success set is an interval of a sorted 1-D action grid: each
    scenario adds one to a contiguous run of actions (a difference array).

    Args:
        lo, hi: ``[E, N]`` open interval ends per scenario.
        mask: ``[E, N]`` retained scenarios.
        actions: ``[A]`` strictly increasing action grid.

    Returns:
        ``[E, A]`` integer counts, identical to counting ``lo < a < hi`` directly.
    """
    actions = np.asarray(actions, dtype=float)
    n_e, n_a = mask.shape[0], actions.shape[0]
    first = np.searchsorted(actions, lo, side="right")  # first a > lo
    last = np.searchsorted(actions, hi, side="left")  # one past the last a < hi
    live = mask & (first < last)
    offset = (np.arange(n_e, dtype=np.int64) * (n_a + 1))[:, None]
    size = n_e * (n_a + 1)
    starts = np.bincount((first + offset)[live], minlength=size)
    stops = np.bincount((last + offset)[live], minlength=size)
    diff = (starts - stops).reshape(n_e, n_a + 1)
    return np.cumsum(diff, axis=1)[:, :n_a]


def scaled_interval_success_counts(centre: np.ndarray, half: np.ndarray, margin: float, mask: np.ndarray,
                                   actions: np.ndarray) -> np.ndarray:
    """:func:`interval_success_counts` of the intervals ``centre -+ half * margin`` (a model's
    ``success_interval_parts``), identical to counting over ``model.success_interval``."""
    width = np.multiply(half, margin)
    return interval_success_counts(centre - width, centre + width, mask, actions)


def margin_success_counts(centre: np.ndarray, half: np.ndarray, margins: np.ndarray, mask: np.ndarray,
                          actions: np.ndarray) -> np.ndarray:
    """:func:`scaled_interval_success_counts` under each of several margins ``[M, E, A]``.

    What a margin search scores: the same retained scenarios under every margin ``gamma``.
    This reference counts margin by margin; a compiled kernel counts every margin in one visit
    of the scenarios (``probecommit.accel.executors``), the same integers.
    """
    return np.stack([scaled_interval_success_counts(centre, half, float(g), mask, actions) for g in margins])


def margin_choices(successes: np.ndarray, kept: np.ndarray, ties: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every margin's action and its score from its success counts: ``(index [M, E], score [M, E])``.

    ``successes[M, E, A]``: retained scenarios under which each action succeeds at each margin;
    ``kept[E]``: the retained count; ``ties[M, E, A]``: each margin's tie-break costs, or ``[1, E, A]``
    when every margin's are the same. The score is the failure fraction ``(kept - successes) / max(kept, 1)``
    (as :func:`retained_scores` makes it) and the action :func:`select_action`'s, margin by margin (its
    steps are row by row, so every margin's rows go in one call).
    """
    scores = (kept[None, :, None] - successes) / np.maximum(kept, 1)[None, :, None]
    ties = np.broadcast_to(ties, scores.shape)
    index = select_action(scores.reshape(-1, scores.shape[-1]), ties.reshape(-1, ties.shape[-1])).reshape(scores.shape[:2])
    return index, np.take_along_axis(scores, index[:, :, None], axis=2)[:, :, 0]


@dataclass(frozen=True)
class SetKernels:
    """The set executors' hot steps, injected into :class:`ProbeRobust`: the NumPy definitions by
    default; the runner injects the compiled ones (``probecommit.accel``).

    Attributes:
        affine_interval_success_counts: ``(scenarios, affine, margin, mask, actions) -> (counts, kept)``
            for a model whose interval parts are affine in its latents (``success_interval_affine``),
            read in place; None: the parts are formed and counted by ``scaled_interval_success_counts``.
    """

    retained_summary: Callable[..., tuple[np.ndarray, ...]] = retained_summary
    interval_success_counts: Callable[..., np.ndarray] = interval_success_counts
    scaled_interval_success_counts: Callable[..., np.ndarray] = scaled_interval_success_counts
    affine_interval_success_counts: Callable[..., tuple[np.ndarray, np.ndarray]] | None = None
    #: ``(centre, half, margins[M], mask, actions) -> [M, E, A]``: a margin search's counts.
    margin_success_counts: Callable[..., np.ndarray] = margin_success_counts
    #: ``(successes[M, E, A], kept[E], ties[M, E, A]) -> (index, score)``: a margin search's choices.
    margin_choices: Callable[..., tuple[np.ndarray, np.ndarray]] = margin_choices


#: The NumPy reference.
NUMPY_KERNELS = SetKernels()


def scenario_max_loss(losses: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Scenario minimax score: the maximum loss over retained scenarios ``[E, A]``."""
    return np.max(np.where(mask[:, None, :], losses, -np.inf), axis=-1)


def prior_expected_loss(losses: np.ndarray) -> np.ndarray:
    """Mean loss over a prior sample: ``losses[A, S] -> [A]`` (Blind-Bayes objective)."""
    return np.mean(np.asarray(losses, dtype=float), axis=-1)


#: Bytes of one block of the ``[actions, prior sample]`` loss matrix :func:`blocked_prior_expected_loss`
#: computes at once (the model's temporaries are a few more of the same size).
PRIOR_LOSS_BLOCK_BYTES = 16 * 1024**2


def blocked_prior_expected_loss(model: Any, sample: np.ndarray, context: np.ndarray | None = None,
                                block_bytes: int = PRIOR_LOSS_BLOCK_BYTES) -> np.ndarray:
    """``prior_expected_loss(model.loss(model.action_grid, sample, context))``, a block of grid actions at a time.

    Each action's mean is over its own row, the same numbers in the same order whatever else the
    block holds, so the answer is bit for bit the whole matrix's; but the matrix (2805 actions x
    5000 draws for a 2-D push target: 112 MB, and the loss's temporaries as many again) never
    exists at once: it set the memory peak of a reproduction's breadth target (issue 42).
    """
    grid = model.action_grid
    rows = max(1, int(block_bytes) // (8 * max(1, len(sample))))
    # Blocks of nearly equal size, never one action alone: a one-row matrix product (a model's
    # ``actions @ target``) takes BLAS's vector path, whose rounding differs in the last bit.
    blocks = min(-(-len(grid) // rows), max(1, len(grid) // 2))
    edges = np.linspace(0, len(grid), blocks + 1).round().astype(int)
    return np.concatenate([prior_expected_loss(model.loss(grid[a:b], sample, context))
                           for a, b in zip(edges[:-1], edges[1:])], axis=-1)


def scenario_scores(model: Any, scenarios: np.ndarray, mask: np.ndarray, context: np.ndarray | None = None,
                    parts: tuple[np.ndarray, np.ndarray] | None = None,
                    kernels: SetKernels = NUMPY_KERNELS) -> np.ndarray:
    """Scenario score of every grid action ``[E, A]`` over the retained scenarios.

    Binary loss: failure fraction (exact integer counts over a retained count); the
    interval-counting fast path is used when the model declares ``success_interval_parts``
    (or only ``success_interval``). Continuous loss: the maximum loss over the retained
    scenarios.

    Args:
        parts: ``model.success_interval_parts(scenarios)`` if already computed (they do not
            depend on the margin: a margin search passes them for every margin).
    """
    if model.binary_loss:
        failures, retained = _failure_counts(model, scenarios, mask, context, parts, kernels)
        return failures / np.maximum(retained, 1)[:, None]
    return blocked_max_loss(model, scenarios, mask, context)


#: Bytes of one ``[episodes, actions, scenarios]`` loss block :func:`blocked_max_loss` computes at once. Darts
#: units (8 episodes x 1483 actions): 8 MiB blocks took 0.72x the CPU of 32 MiB ones (they stay in cache) and the
#: process 40-55 MB less resident memory.
SCENARIO_BLOCK_BYTES = 8 * 1024**2


def blocked_max_loss(model: Any, scenarios: np.ndarray, mask: np.ndarray, context: np.ndarray | None = None,
                     block_bytes: int = SCENARIO_BLOCK_BYTES) -> np.ndarray:
    """``scenario_max_loss(model.loss(model.action_grid, scenarios, context), mask)``, a block of scenarios at a time.

    A maximum is exact in any grouping, and each block's losses are the same numbers (the model's
    action terms do not depend on the scenarios), so the scores are bit for bit the whole array's
    (as :func:`retained_scores`' blocks); but ``[E, A, N]`` and the loss's temporaries (a 2-D push
    unit: 6 x 2805 x 1024, 138 MB each, three at once) never exist whole (issue 42: the memory peak
    of the breadth target).
    """
    n_episodes, n = mask.shape
    step = max(1, int(block_bytes) // (8 * max(1, n_episodes * len(model.action_grid))))
    if step >= n:
        return scenario_max_loss(model.loss(model.action_grid, scenarios, context), mask)
    return np.maximum.reduce([scenario_max_loss(model.loss(model.action_grid, scenarios[:, i:i + step], context),
                                                mask[:, i:i + step]) for i in range(0, n, step)])


def _in_place_affine(model: Any, kernels: SetKernels) -> tuple[int, int, float, float] | None:
    """The model's affine success-interval parts (``success_interval_affine``) when the kernels can
    count with them in place, so the ``[E, N]`` parts need not be formed; else None."""
    if kernels.affine_interval_success_counts is None:
        return None
    return model.success_interval_affine()


def _failure_counts(model: Any, scenarios: np.ndarray, mask: np.ndarray, context: np.ndarray | None,
                    parts: tuple[np.ndarray, np.ndarray] | None,
                    kernels: SetKernels = NUMPY_KERNELS) -> tuple[np.ndarray, np.ndarray]:
    """Retained scenarios that fail under each grid action ``[E, A]`` (integers), binary loss,
    and how many are retained ``[E]``."""
    grid = np.asarray(model.action_grid, dtype=float).reshape(-1)
    affine = _in_place_affine(model, kernels)
    if affine is not None and parts is None:  # both parts read from the scenarios inside the kernel
        counts, retained_count = kernels.affine_interval_success_counts(scenarios, affine, model.margin, mask, grid)
        return retained_count[:, None] - counts, retained_count
    retained_count = mask.sum(axis=-1)
    parts = model.success_interval_parts(scenarios) if parts is None else parts
    if parts is not None:
        successes = kernels.scaled_interval_success_counts(*parts, model.margin, mask, grid)
    elif (interval := model.success_interval(scenarios)) is not None:  # a model with only the interval
        successes = kernels.interval_success_counts(*interval, mask, grid)
    else:
        return np.sum(model.loss(model.action_grid, scenarios, context) & mask[:, None, :], axis=-1), retained_count
    return retained_count[:, None] - successes, retained_count


@dataclass(frozen=True)
class Belief:
    """What an executor decides from: a batch of particle beliefs at one budget.

    Attributes:
        particles: ``[E, N, d]`` latent hypotheses.
        weights: ``[E, N]`` normalized weights.
        z: ``[E, N]`` each particle's decision coordinate (``model.decision(particles)``).
        shared: What a set builds from the belief alone, whatever its threshold (a grown set's
            tie-break reference and decision-coordinate extremes), kept here by the caller that holds
            the belief: a calibration commits one belief under ``t_k`` and under ``t``.
    """

    particles: np.ndarray
    weights: np.ndarray
    z: np.ndarray
    shared: dict = field(default_factory=dict, repr=False, compare=False)


@runtime_checkable
class Executor(Protocol):
    """One executor, injected into the runner (Stone Soup style): it holds its model and decides.

    Attributes:
        method: The label its rows carry in the episode table's ``method`` column.
        on_prior: True for a blind executor, which commits once on the prior belief (k = 0);
            False for one that commits after every probe budget.
    """

    method: str
    on_prior: bool

    def decide(self, belief: Belief, threshold: float, context: np.ndarray | None = None,
               memo: dict | None = None) -> "Commitment":
        """Commit for every episode of ``belief``.

        Args:
            threshold: Retained mass ``nu`` or conformal threshold ``t`` (set executors).
            context: ``[E, c]`` observed context, if the family has one.
            memo: A dict kept by the caller per (executor, budget, threshold) across commits that
                differ only in the model's margin: what does not depend on the margin goes there.
        """

    def with_model(self, model: Any) -> "Executor":
        """This executor deciding with ``model`` (a margin override)."""

    @property
    def memo_tag(self) -> Any:
        """What besides method, budget and threshold its memo depends on (a cache key part)."""


@dataclass
class Commitment:
    """What an executor decided for a batch of episodes.

    Attributes:
        index: ``[E]`` action grid indices.
        score: ``[E]`` modeled score of the chosen action (failure fraction or max miss).
        mask: ``[E, N]`` particles in the retained set (all of them for a grown set).
        lo, hi: ``[E]`` the retained set's interval in the decision coordinate.
    """

    index: np.ndarray
    score: np.ndarray
    mask: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


def grown_set(model: Any, particles: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The set for a threshold ``t > 1``: the hull grown by ``(t - 1) D`` on each side.

    It is represented by all ``N`` particles plus ``GROWN_SET_POINTS`` scenarios evenly
    spaced across the grown decision-coordinate interval; the model fills their other
    latents (``model.grown_scenarios``; insertion: the particles' median clearance).

    Returns:
        Scenarios ``[E, N + 9, d]`` and the grown interval ``(lo, hi)`` per episode.
    """
    points, lo, hi = grown_points(model, particles, threshold)
    return np.concatenate([particles, points], axis=1), lo, hi


def grown_points(model: Any, particles: np.ndarray, threshold: float, z: np.ndarray | None = None,
                 shared: dict | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``GROWN_SET_POINTS`` scenarios a grown set adds to the particles ``[E, 9, d]``, and
    its interval ``(lo, hi)`` (see :func:`grown_set`); ``z`` is ``model.decision(particles)`` when the
    caller has it (a contiguous copy: its extremes are read several times as fast as a strided view's),
    and ``shared`` keeps those extremes, and the points' other latents where the model's
    ``grown_scenarios`` takes them (``takes_centre``), for the belief's other thresholds (:attr:`Belief.shared`)."""
    shared = {} if shared is None else shared
    if "extremes" not in shared:
        z = model.decision(particles) if z is None else z
        shared["extremes"] = z.min(axis=1), z.max(axis=1)
    z_min, z_max = shared["extremes"]
    grow = (threshold - 1.0) * model.decision_domain_width
    lo, hi = z_min - grow, z_max + grow
    z_points = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, GROWN_SET_POINTS)[None, :]
    if not getattr(model.grown_scenarios, "takes_centre", False):  # a family's own: all of it per threshold
        return model.grown_scenarios(particles, z_points), lo, hi
    key = ("centre", type(model).grown_centre)  # the particles' median, once per belief (docs/decisions.md, "cal4:")
    if key not in shared:
        shared[key] = model.grown_centre(particles)
    return model.grown_scenarios(particles, z_points, centre=shared[key]), lo, hi


@dataclass
class RetainedSet:
    """The scenario set an executor scores, built from a belief and a threshold.

    It does not depend on the model's margin, so a margin search builds it once per
    threshold and rescores it per margin (:meth:`ProbeRobust.choose`). A grown set holds
    the belief's particles (not a copy) and the points it adds, scored as two blocks.

    Attributes:
        particles: ``[E, N, d]`` the belief's particles.
        mask: ``[E, N]`` retained particles (all of them for a grown set).
        lo, hi: ``[E]`` the set's decision-coordinate interval.
        reference: ``[E, d]`` the tie-break reference.
        grown: ``[E, G, d]`` the scenarios a grown set (t > 1) adds, every one retained; None otherwise.
    """

    particles: np.ndarray
    mask: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    reference: np.ndarray
    grown: np.ndarray | None = None
    #: ``model.success_interval_parts`` of each block per model kind and variant, filled on first use.
    _interval_parts: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def scenarios(self) -> np.ndarray:
        """Every scenario scored ``[E, S, d]``: the particles, then the grown points (a new array then)."""
        return self.particles if self.grown is None else np.concatenate([self.particles, self.grown], axis=1)

    @property
    def scenario_mask(self) -> np.ndarray:
        """``[E, S]`` which of :attr:`scenarios` are retained."""
        if self.grown is None:
            return self.mask
        return np.concatenate([self.mask, np.ones(self.grown.shape[:2], dtype=bool)], axis=1)

    def blocks(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``(scenarios, mask)`` of each block scored: the particles, then any grown points."""
        if self.grown is None:
            return [(self.particles, self.mask)]
        return [(self.particles, self.mask), (self.grown, np.ones(self.grown.shape[:2], dtype=bool))]

    def interval_parts(self, model: Any) -> list[tuple[np.ndarray, np.ndarray] | None]:
        """The model's success-interval parts of each block, computed once per set and model
        (kind and variant label): they do not depend on the margin, which a margin search varies."""
        key = (type(model), model.variant)
        if key not in self._interval_parts:
            self._interval_parts[key] = [model.success_interval_parts(block) for block, _ in self.blocks()]
        return self._interval_parts[key]


def retained_scores(model: Any, retained: RetainedSet, context: np.ndarray | None = None,
                    kernels: SetKernels = NUMPY_KERNELS) -> np.ndarray:
    """:func:`scenario_scores` of every grid action ``[E, A]`` over a retained set, block by block.

    The same numbers as scoring :attr:`RetainedSet.scenarios` at once: a binary loss sums
    integer failure counts over the blocks before dividing by the retained count, and a
    continuous loss takes the larger of the blocks' maxima; a grown set's particles are
    never copied.
    """
    blocks = retained.blocks()
    # Parts formed once per set for a margin search, unless a compiled kernel reads them in place.
    formed = model.binary_loss and _in_place_affine(model, kernels) is None
    if len(blocks) == 1:
        scenarios, mask = blocks[0]
        parts = retained.interval_parts(model)[0] if formed else None
        return scenario_scores(model, scenarios, mask, context, parts, kernels)
    if model.binary_loss:
        parts = retained.interval_parts(model) if formed else [None] * len(blocks)
        counted = [_failure_counts(model, scenarios, mask, context, part, kernels)
                   for (scenarios, mask), part in zip(blocks, parts)]
        failures = sum(failed for failed, _ in counted)
        kept = np.maximum(sum(n_kept for _, n_kept in counted), 1)
        return failures / kept[:, None]
    return np.maximum.reduce([scenario_max_loss(model.loss(model.action_grid, scenarios, context), mask)
                              for scenarios, mask in blocks])


#: Set constructions at t = 1: the paper's top-weight prefix, or every particle.
PLATEAU_MODES = ("prefix", "hull")
#: In ``hull`` mode a threshold this close to one is the plateau: the cumulative mass of
#: normalized float weights ends a few ulps short of one, and only particles of weight
#: below ``MASS_TOLERANCE`` (~1e-12 each, so at most N * 1e-12 in all) can lie past it.
PLATEAU_EPSILON = 1e-9


@dataclass
class ProbeRobust:
    """Probe-Robust(k): the set objective over the retained top-weight set of a belief.

    Args:
        model: The task model scoring actions.
        plateau: The set at ``t = 1``. ``"prefix"`` (the paper): the shortest prefix
            reaching mass one, which stops before the zero-weight particles, so a truth
            spanned only by them has score ``s = 1`` and is still not covered (the
            paper's named exception). ``"hull"``: every particle, so ``s <= t`` implies
            coverage for every ``t`` and the split-conformal guarantee has no exception.
        kernels: The hot steps (:class:`SetKernels`; NumPy's by default).
    """

    model: Any
    plateau: str = "prefix"
    kernels: SetKernels = NUMPY_KERNELS

    def __post_init__(self) -> None:
        if self.plateau not in PLATEAU_MODES:
            raise ValueError(f"plateau must be one of {', '.join(PLATEAU_MODES)}, got {self.plateau!r}")

    def retain(self, particles: np.ndarray, weights: np.ndarray, threshold: float,
               z: np.ndarray | None = None, shared: dict | None = None) -> RetainedSet:
        """The retained set at mass ``nu`` (``<= 1``) or the grown set of a threshold ``t > 1``;
        ``z`` is ``model.decision(particles)`` when the caller has it (not computed, or copied, again),
        ``shared`` the belief's :attr:`Belief.shared` (what a set of every particle reads is built once)."""
        model = self.model
        shared = {} if shared is None else shared
        if "reference" not in shared and (threshold > 1 or self.plateau == "hull"):
            shared["reference"] = belief_reference(particles, weights)  # every particle's: any threshold's
        if self.plateau == "hull" and 1 - PLATEAU_EPSILON <= threshold <= 1:
            mask = np.ones_like(weights, dtype=bool)
            lo, hi = masked_interval(model.decision(particles), mask)
            return RetainedSet(particles, mask, lo, hi, shared["reference"])
        if threshold <= 1:
            mask, lo, hi, reference = self.kernels.retained_summary(
                weights, threshold, model.decision(particles) if z is None else z, particles)
            return RetainedSet(particles, mask, lo, hi, reference)
        points, lo, hi = grown_points(model, particles, threshold, z, shared)
        return RetainedSet(particles, np.ones_like(weights, dtype=bool), lo, hi, shared["reference"], points)

    def choose(self, retained: RetainedSet, context: np.ndarray | None = None) -> Commitment:
        """Score every grid action over a retained set and pick one per episode."""
        model = self.model
        scores = retained_scores(model, retained, context, self.kernels)
        index = select_action(scores, model.tie_break_cost(model.action_grid, retained.reference, context))
        return Commitment(index, np.take_along_axis(scores, index[:, None], axis=1)[:, 0], retained.mask,
                          retained.lo, retained.hi)

    method = "probe_robust"
    on_prior = False

    @property
    def memo_tag(self) -> str:
        return self.plateau

    def with_model(self, model: Any) -> "ProbeRobust":
        return replace(self, model=model)

    def decide(self, belief: Belief, threshold: float, context: np.ndarray | None = None,
               memo: dict | None = None) -> Commitment:
        """:class:`Executor`'s interface: the retained set (kept in ``memo``: it does not depend
        on the margin) scored and one action chosen per episode."""
        memo = {} if memo is None else memo
        if "retained" not in memo:
            memo["retained"] = self.retain(belief.particles, belief.weights, threshold, belief.z, belief.shared)
        retained = memo["retained"]
        swept = memo.get("margins", {}).get(float(self.model.margin))
        if swept is not None:  # chosen already by a margin sweep of this set (decide_margins)
            return Commitment(*swept, retained.mask, retained.lo, retained.hi)
        return self.choose(retained, context)

    def decide_margins(self, belief: Belief, threshold: float, margins: Sequence[float],
                       context: np.ndarray | None = None, memo: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`choose_margins` on the retained set :meth:`decide` keeps in ``memo``; each margin's
        aims and scores are kept there too, so a later :meth:`decide` under one of those margins
        (a calibration's commit at the model's margin beside its margin search) is not scored again:
        ``choose_margins`` equals ``choose`` margin by margin (tested), so it is the same commitment."""
        memo = {} if memo is None else memo
        if "retained" not in memo:
            memo["retained"] = self.retain(belief.particles, belief.weights, threshold, belief.z, belief.shared)
        index, score = self.choose_margins(memo["retained"], margins, context)
        memo["margins"] = {float(g): (index[m], score[m]) for m, g in enumerate(margins)}
        return index, score

    def choose_margins(self, retained: RetainedSet, margins: Sequence[float],
                       context: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`choose` under each margin: the aims ``[M, E]`` and their scores ``[M, E]``.

        Equal, margin by margin, to ``self.with_model(model.with_margin(g)).choose(retained, context)``
        (tested). Why: a margin search scores one retained set under dozens of margins; for a
        binary loss with success-interval parts (which do not depend on the margin) every margin's
        counts come from one count (:attr:`SetKernels.margin_success_counts`) of integers, so
        every score and choice is the same as margin by margin. Other models choose margin by margin.
        """
        margins = [float(g) for g in margins]
        models = [self.model.with_margin(g) for g in margins]
        parts = retained.interval_parts(self.model) if self.model.binary_loss else [None]
        if any(part is None for part in parts) or not all(0.0 < g < np.inf for g in margins):
            chosen = [self.with_model(model).choose(retained, context) for model in models]
            return np.stack([c.index for c in chosen]), np.stack([np.asarray(c.score, dtype=float) for c in chosen])
        grid = np.asarray(self.model.action_grid, dtype=float).reshape(-1)
        successes, kept = None, 0
        for (_, mask), (centre, half) in zip(retained.blocks(), parts):
            counts = self.kernels.margin_success_counts(centre, half, np.asarray(margins), mask, grid)
            successes = counts if successes is None else np.add(successes, counts, out=successes)  # [M, E, A] once
            kept = kept + mask.sum(axis=-1)
        # As retained_scores: integer failures over the retained count, then select_action per margin.
        return self.kernels.margin_choices(successes, kept, _margin_ties(models, retained.reference, context))

    def act(self, particles: np.ndarray, weights: np.ndarray, threshold: float,
            context: np.ndarray | None = None) -> Commitment:
        """Commit for every episode of a belief batch.

        Args:
            particles: ``[E, N, d]``.
            weights: ``[E, N]`` normalized.
            threshold: Retained mass ``nu`` (``<= 1``) or a conformal threshold ``t > 1``
                (the grown set).
            context: ``[E, c]`` observed context, if the family has one.
        """
        return self.choose(self.retain(particles, weights, threshold), context)


def _margin_ties(models: Sequence[Any], reference: np.ndarray, context: np.ndarray | None) -> np.ndarray:
    """Each margin's tie-break costs ``[M, E, A]``, or ``[1, E, A]`` when every margin's are the same bits
    (a family whose tie cost does not read the margin): one ``[E, A]`` block read for every margin
    instead of ``M`` copies stacked (``margin_choices`` takes either)."""
    if _one_tie_cost(models):  # the same bits for every margin, known without computing them
        return np.asarray(models[0].tie_break_cost(models[0].action_grid, reference, context), dtype=float)[None]
    ties = [model.tie_break_cost(model.action_grid, reference, context) for model in models]
    first = np.asarray(ties[0], dtype=float)
    if all(np.asarray(t, dtype=float).tobytes() == first.tobytes() for t in ties[1:]):
        return first[None]
    return np.stack(ties)


def _one_tie_cost(models: Sequence[Any]) -> bool:
    """Whether every model's tie cost is the same function of the actions and reference alone
    (``tie_break_cost.reads_only_reference``) on the same action grid: then one block serves every margin."""
    first = models[0]
    return all(type(model) is type(first) and getattr(model.tie_break_cost, "reads_only_reference", False)
               and np.array_equal(model.action_grid, first.action_grid) for model in models)


class BlindRobust(ProbeRobust):
    """Blind-Robust: the same set objective applied to the unprobed prior cloud (k = 0)."""

    method = "blind_robust"
    on_prior = True


@dataclass
class BlindBayes:
    """Blind-Bayes: the prior-expected-loss optimum over a fixed large prior sample.

    A converged prior-averaged policy: the expectation is computed directly over
    ``prior_sample`` (one action per distinct context), not learned.

    Args:
        model: The task model.
        prior_sample: ``[S, d]`` draws from the prior.
    """

    model: Any
    prior_sample: np.ndarray
    #: Each context's ``act_one`` answer, by the context's bytes: the policy is fixed, and a run's
    #: units (one instance each, say) share contexts, so each is computed once per executor.
    answers: dict = field(default_factory=dict, init=False, compare=False, repr=False)

    method = "blind_bayes"
    on_prior = True
    memo_tag = None

    def with_model(self, model: Any) -> "BlindBayes":
        """Itself: the policy is fixed when built (by the prior sample and the model given then),
        so a margin override rescoring the set executors leaves Blind-Bayes's actions as they were."""
        return self

    def decide(self, belief: Belief, threshold: float, context: np.ndarray | None = None,
               memo: dict | None = None) -> Commitment:
        """:class:`Executor`'s interface: the prior optimum per context; its "set" is every
        particle of the belief (the threshold does not apply)."""
        mask = np.ones_like(belief.weights, dtype=bool)
        lo, hi = masked_interval(belief.z, mask)
        index, expected = self.act(belief.weights.shape[0], context)
        return Commitment(index, expected, mask, lo, hi)

    def act_one(self, context: np.ndarray | None = None) -> tuple[int, float]:
        """Action index and its prior expected loss for one context (or none)."""
        model, sample = self.model, self.prior_sample
        expected = blocked_prior_expected_loss(model, sample, context)
        reference = sample.mean(axis=0)[None, :]
        cost = model.tie_break_cost(model.action_grid, reference, None if context is None else np.asarray(context)[None])
        index = int(select_action(expected[None, :], cost)[0])
        return index, float(expected[index])

    def _answer(self, context: np.ndarray) -> tuple[int, float]:
        """``act_one(context)``, computed once per distinct context (exact: keyed by its float64 bytes)."""
        key = np.ascontiguousarray(context, dtype=float).tobytes()
        answer = self.answers.get(key)
        if answer is None:
            answer = self.answers[key] = self.act_one(context)
        return answer

    def act(self, n_episodes: int, context: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(index[E], expected[E])`` for a batch; computed once per distinct context."""
        if context is None or np.asarray(context).shape[-1] == 0:
            index, expected = self.act_one(None)
            return np.full(n_episodes, index), np.full(n_episodes, expected)
        context = np.asarray(context, dtype=float)
        unique, inverse = np.unique(context, axis=0, return_inverse=True)
        answers = [self._answer(row) for row in unique]
        inverse = np.asarray(inverse).reshape(-1)
        return (np.array([answers[i][0] for i in inverse], dtype=np.int64),
                np.array([answers[i][1] for i in inverse], dtype=float))
