"""Analytic insertion model (paper Sec. III, Eq. 2). NumPy only; all lengths in mm.

theta = (x_hole, c): hole centre and clearance scale. The slot half-gap is
``hg(c) = 4 + 0.6 c``; a tap at ``u`` reads the pocket floor (-15 mm) when
``|u - x_hole| < hg(c) + boundary_offset`` and the plate top (0 mm) otherwise.
The deployed model uses ``boundary_offset = -r = -1.2`` mm, the corrected one
``+delta``. The modeled loss is failure when ``|a - x_hole| >= gamma * w(c)`` with
capture half-width ``w(c) = 0.6 c + 1.1`` mm and margin ``gamma`` (1 = no margin),
evaluated as the open interval test ``x - gamma w < a < x + gamma w``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.base import TaskModelBase

TIP_RADIUS_MM = 1.2
POCKET_DEPTH_MM = 15.0
PLATE_TOP_MM = 0.0
#: The paper's MuJoCo-fitted boundary offset; replaced by our own scan's value in configs.
PAPER_DELTA_MM = 0.905
#: Prior box on (x_hole [mm], c).
PRIOR_LOW = (-10.0, 0.7)
PRIOR_HIGH = (10.0, 1.3)


def half_gap(c: np.ndarray) -> np.ndarray:
    """Slot half-gap ``hg(c) = 4 + 0.6 c`` in mm (a new array; the same bits as ``4.0 + 0.6 * c``)."""
    gap = np.multiply(0.6, c, dtype=float)
    gap += 4.0
    return gap


#: The modeled capture half-width ``w(c) = CAPTURE_SLOPE c + CAPTURE_INTERCEPT`` (mm).
CAPTURE_SLOPE, CAPTURE_INTERCEPT = 0.6, 1.1


def capture_half_width(c: np.ndarray) -> np.ndarray:
    """Modeled capture half-width ``w(c) = 0.6 c + 1.1`` in mm."""
    return CAPTURE_SLOPE * np.asarray(c) + CAPTURE_INTERCEPT


@dataclass(frozen=True)
class InsertionModel(TaskModelBase):
    """The insertion task model; variants are parameters, not copies.

    Args:
        boundary_offset: Offset added to ``hg(c)`` for the pocket-reading boundary (mm).
        variant: Label stored with every episode this model scores.
        sigma: Observation noise the likelihood assumes (mm).
        margin: ``gamma``, the capture window shrink used when scoring aims.
        prior_low, prior_high: Box prior on ``(x_hole, c)``.
    """

    boundary_offset: float = -TIP_RADIUS_MM
    variant: str = "deployed"
    sigma: float = 0.5
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.6, 0.006]))

    # name, latent_names and context_names: from the declaration (probecommit.tasks.insertion).
    #: Nine tap positions, -12..12 mm in 3 mm steps ``[9, 1]``.
    probe_grid = np.arange(-12.0, 12.0 + 1e-9, 3.0)[:, None]
    #: Aims on a 0.5 mm grid over [-10, 10] mm ``[41, 1]``.
    action_grid = np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10)[:, None]
    binary_loss = True
    decision_domain_width = 20.0
    #: Readings a tap can physically give (mm): above the pocket floor's noise band to the start height.
    observation_range = (-17.0, 2.0)
    probe_dim = 1
    observation_dim = 1
    action_dim = 1

    def __post_init__(self) -> None:
        self.check_sigma_and_margin()
        if np.any(np.asarray(self.prior_high) <= np.asarray(self.prior_low)):
            raise ValueError("prior box must have high > low in every coordinate")

    @classmethod
    def deployed(cls, **kwargs) -> "InsertionModel":
        """The boundary as deployed: ``hg(c) - r``."""
        return cls(boundary_offset=-TIP_RADIUS_MM, variant="deployed", **kwargs)

    @classmethod
    def corrected(cls, delta: float = PAPER_DELTA_MM, **kwargs) -> "InsertionModel":
        """The corrected boundary ``hg(c) + delta``."""
        return cls(boundary_offset=float(delta), variant="corrected", **kwargs)

    def decision(self, theta: np.ndarray) -> np.ndarray:
        """The hole position ``x_hole``."""
        return np.asarray(theta)[..., 0]

    def tie_break_cost(self, actions: np.ndarray, reference: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Distance of each aim from the reference's hole position ``[E, A]``."""
        a = np.asarray(actions, dtype=float).reshape(-1)
        return np.abs(a[None, :] - np.asarray(reference, dtype=float)[:, 0][:, None])

    #: It reads the actions and the reference alone (no margin, no other field): a margin search computes
    #: one block for all its margins instead of one per margin (``core.executors._margin_ties``).
    tie_break_cost.reads_only_reference = True  # type: ignore[attr-defined]

    def reads_pocket(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Whether a tap at ``u[E]`` (or ``[E, 1]``) reads the pocket for each particle ``[E, N]``."""
        theta = np.asarray(theta)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        # |u - x| < hg(c) + offset, with the temporaries reused in place (same operations, same bits).
        distance = np.subtract(u, theta[..., 0], dtype=float)
        np.abs(distance, out=distance)
        boundary = half_gap(theta[..., 1])
        boundary += self.boundary_offset
        return np.less(distance, boundary)

    #: The two readings a tap can predict, ``(pocket floor, plate top)`` (see :meth:`add_reading_log_likelihood`).
    reading_levels = (PLATE_TOP_MM - POCKET_DEPTH_MM, PLATE_TOP_MM)

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        pocket = self.reads_pocket(u, theta)
        return np.where(pocket, *self.reading_levels)[..., None]

    def add_reading_log_likelihood(self, u: np.ndarray, theta: np.ndarray, log_weights: np.ndarray,
                                   level_ll: np.ndarray) -> np.ndarray:
        """``log_weights + loglik`` where each particle's log-likelihood is that of its predicted level.

        A tap predicts one of two readings (:attr:`reading_levels`), so an arithmetic likelihood
        takes one of two values per episode, ``level_ll[E, 2]``; this picks each particle's
        without forming ``predict``'s ``[E, N, 1]`` array (a compiled pass unless ``PROBECOMMIT_KERNELS=numpy``).
        The same bits as ``log_weights + likelihood.log_likelihood(y, predict(u, theta))``
        (tested).
        """
        from probecommit.accel import mode

        # The kernel computes this class's reads_pocket; a subclass with its own (the rig) takes NumPy's.
        if mode() == "numba" and type(self).reads_pocket is InsertionModel.reads_pocket:
            from probecommit.tasks.insertion.kernels import slot_tap_log_weights

            return slot_tap_log_weights(u, theta, log_weights, level_ll, self.boundary_offset)
        return log_weights + np.where(self.reads_pocket(u, theta), level_ll[:, :1], level_ll[:, 1:])

    def success_interval_parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The open interval of aims that succeed, ``x - gamma w(c) < a < x + gamma w(c)``, as
        ``(x, w(c))``; :meth:`success_interval` scales ``w`` by the margin.

        This is the definition of the modeled loss; ``loss`` and the executor's
        interval-counting fast path both use it, so they agree bit for bit.
        """
        theta = np.asarray(theta)
        # In place, the same operations and order as 0.6 c + 1.1: bit-identical, one temporary.
        window = np.multiply(theta[..., 1], CAPTURE_SLOPE)
        window += CAPTURE_INTERCEPT
        return theta[..., 0], window

    def success_interval_affine(self) -> tuple[int, int, float, float] | None:
        """``(0, 1, 0.6, 1.1)``: :meth:`success_interval_parts` is ``(x, 0.6 c + 1.1)``; None for a
        subclass with parts of its own (the rig's window)."""
        if type(self).success_interval_parts is not InsertionModel.success_interval_parts:
            return None
        return 0, 1, CAPTURE_SLOPE, CAPTURE_INTERCEPT

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled failure ``[E, A, N]`` (or ``[A, S]`` for ``theta[S, d]``); actions ``[A]`` or ``[A, 1]``."""
        lo, hi = self.success_interval(theta)
        a = np.asarray(actions, dtype=float).reshape(-1)
        if lo.ndim == 1:  # [S] -> [A, S]
            return ~((lo[None, :] < a[:, None]) & (a[:, None] < hi[None, :]))
        return ~((lo[:, None, :] < a[None, :, None]) & (a[None, :, None] < hi[:, None, :]))
