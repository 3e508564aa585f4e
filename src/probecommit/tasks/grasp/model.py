"""Grasp force-balance model: squeeze to learn the hold force, then grip gently (paper Table II).

theta = (mu, m): friction coefficient between the pads and the object, and the object's
mass (kg). A parallel-jaw grip pressing each side with force ``F`` holds the object
against its weight and the lift's acceleration ``a`` when ``2 mu F >= m (g + a)``:

    F_lift(theta) = m (g + a) / (2 mu).

The object is delicate (a fruit, a paper cup): the task allows at most ``CRUSH_RATIO``
(1.5) times the force that holds it. A grip ``F`` succeeds when
``F_lift < F < 1.5 F_lift``; with margin ``gamma`` the window shrinks about its centre
(``gamma = 1``: the window itself). The loss is failure (binary).

A probe is a *squeeze*: holding the object in the air, the gripper relaxes to a known
force ``u`` for ``SQUEEZE_S`` = 50 ms and reads how far the object slid between the pads
(mm, ``sigma`` = 2 mm): ``slip = (1/2) T^2 g (1 - u / F_hold)^+`` with
``F_hold = m g / (2 mu)`` (no lift acceleration during a squeeze). Both latents enter
through ``m / mu`` only: a squeeze identifies exactly the hold force, which is all a
grip needs. The decision coordinate is ``F_lift`` (N).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.core.retained import median_over_particles
from probecommit.tasks.base import TaskModelBase

G = 9.81
#: Lift acceleration of the commit (m/s^2).
LIFT_ACCEL = 2.0
#: Duration of a squeeze probe's relaxation (s).
SQUEEZE_S = 0.05
#: The most a delicate object tolerates, as a multiple of the force that holds it.
CRUSH_RATIO = 1.5
#: Prior box on (mu, m): rubber-to-cardboard friction, 50-500 g objects.
PRIOR_LOW = (0.2, 0.05)
PRIOR_HIGH = (1.0, 0.5)
#: Known squeeze forces (N per pad).
PROBE_FORCES = (0.25, 0.5, 1.0, 2.0, 4.0)
#: Grip forces (N per pad): 0.2 N times 1.02^i up to 5 N (163), the range of a small servo
#: gripper like the paper's arm's; 2 % steps resolve the 1.5x window with about 20 grid points.
ACTION_FORCES = np.round(0.2 * 1.02 ** np.arange(0, int(np.log(25.0) / np.log(1.02)) + 1), 10)


def hold_force(mu: np.ndarray, m: np.ndarray, accel: float = 0.0) -> np.ndarray:
    """Force per pad (N) that holds ``m`` against gravity plus ``accel``: ``m (g + a) / (2 mu)``."""
    return np.asarray(m, dtype=float) * (G + accel) / (2.0 * np.asarray(mu, dtype=float))


def squeeze_slip_mm(u: np.ndarray, mu: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Slip (mm) of the object during a squeeze at force ``u`` (broadcasting)."""
    excess = np.maximum(1.0 - np.asarray(u, dtype=float) / hold_force(mu, m), 0.0)
    return 1000.0 * 0.5 * SQUEEZE_S ** 2 * G * excess


@dataclass(frozen=True)
class GraspModel(TaskModelBase):
    """The grasp task model.

    Args:
        sigma: Observation noise the likelihood assumes (mm).
        margin: ``gamma``: the success window scaled about its centre (1 = none).
        prior_low, prior_high: Box prior on ``(mu, m)``.
        variant: Label stored with every episode this model scores.
    """

    sigma: float = 2.0
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    #: About 2.5 % of each prior width.
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.02, 0.01125]))
    variant: str = "deployed"

    # name, latent_names and context_names: from the declaration (probecommit.tasks.grasp).
    probe_grid = np.array(PROBE_FORCES)[:, None]
    action_grid = ACTION_FORCES[:, None]
    binary_loss = True
    decision_domain_width = float(hold_force(PRIOR_LOW[0], PRIOR_HIGH[1], LIFT_ACCEL)
                                  - hold_force(PRIOR_HIGH[0], PRIOR_LOW[1], LIFT_ACCEL))
    probe_dim = 1
    observation_dim = 1
    action_dim = 1
    #: Slips a squeeze can physically read (mm): none (with noise) up to the free fall's 12.3 mm.
    observation_range = (-10.0, 25.0)

    def __post_init__(self) -> None:
        self.check_sigma_and_margin()
        if np.any(np.asarray(self.prior_low) <= 0):
            raise ValueError("mu and m must be positive")

    def decision(self, theta: np.ndarray) -> np.ndarray:
        """The lift's hold force ``F_lift`` (N)."""
        theta = np.asarray(theta)
        return hold_force(theta[..., 0], theta[..., 1], LIFT_ACCEL)

    def grown_scenarios(self, particles: np.ndarray, z_points: np.ndarray) -> np.ndarray:
        """Scenarios at hold forces ``z``: median mass, ``mu = m (g + a) / (2 z)``."""
        extra = np.repeat(median_over_particles(particles)[:, None, :], z_points.shape[1], axis=1)
        extra[..., 0] = extra[..., 1] * (G + LIFT_ACCEL) / (2.0 * np.maximum(z_points, 1e-6))
        return extra

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Squeeze slip ``[E, N, 1]`` (mm) at forces ``u[E]``."""
        theta = np.asarray(theta, dtype=float)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        return squeeze_slip_mm(u, theta[..., 0], theta[..., 1])[..., None]

    def success_interval_parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Open interval of grip forces that hold without crushing, ``(F_lift, 1.5 F_lift)`` at gamma = 1,
        as its centre and half-width (the half-width scales with the margin)."""
        f_lift = self.decision(theta)
        return 0.5 * (1.0 + CRUSH_RATIO) * f_lift, np.multiply(0.5 * (CRUSH_RATIO - 1.0), f_lift)

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled failure ``[E, A, N]`` (``[A, S]`` for ``theta[S, d]``)."""
        lo, hi = self.success_interval(theta)
        a = np.asarray(actions, dtype=float).reshape(-1)
        if lo.ndim == 1:
            return ~((lo[None, :] < a[:, None]) & (a[:, None] < hi[None, :]))
        return ~((lo[:, None, :] < a[None, :, None]) & (a[None, :, None] < hi[:, None, :]))

    def tie_break_cost(self, actions: np.ndarray, reference: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Distance of each force from the centre of the reference's window ``[E, A]``."""
        a = np.asarray(actions, dtype=float).reshape(-1)
        lo, hi = self.success_interval(np.asarray(reference, dtype=float))
        return np.abs(a[None, :] - (0.5 * (lo + hi))[:, None])
