"""Analytic 1-D push model: a box slides along a line after an impulse (paper Table II).

theta = (mu, m, k_d): Coulomb friction coefficient, mass (kg) and linear damping
(N s/m). An impulse ``J`` (N s) gives the box the speed ``v0 = J / m``; it then obeys

    m dv/dt = -mu m g - k_d v,    v(0) = v0 > 0,

until it stops (static friction holds it after that). With the damping time
``tau = m / k_d`` and the friction-damping speed ``v_c = mu g m / k_d`` the solution is

    v(t) = (v0 + v_c) exp(-t / tau) - v_c,
    t_stop = tau ln(1 + v0 / v_c),
    d(J) = x(t_stop) = tau [v0 - v_c ln(1 + v0 / v_c)].

As ``k_d -> 0`` this tends to the Coulomb-only ``v0^2 / (2 mu g)``; as ``mu -> 0`` to
the damping-only ``tau v0``. ``d`` depends on the three latents through ``(m, tau,
v_c)``, a one-to-one map, so pulses of several magnitudes identify all three in
principle; the noise (5 cm) keeps them partly confounded in practice.

A probe is a known pulse ``u`` (N s) and observes the slide distance ``d(u)`` with
``sigma`` metres of noise; the box is returned to its start pose after each probe.
The action is an impulse on a grid; the context is the target distance; the loss is
the miss ``|d(J) - target|`` (metres), divided by the margin ``gamma``.

The decision coordinate is the friction ``mu`` (latent 0, the default).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.base import TaskModelBase

G = 9.81
#: Smallest friction a grown scenario may have (grown sets can reach past zero).
MIN_FRICTION = 1e-6

#: Prior box on (mu, m, k_d): table-top friction, a 0.5-1.5 kg box, damping time
#: constants m / k_d from 0.17 s to 3 s.
PRIOR_LOW = (0.2, 0.5, 0.5)
PRIOR_HIGH = (0.6, 1.5, 3.0)
#: Known probe pulses (N s).
PROBE_PULSES = (1.0, 2.0, 3.0)
#: Commit impulses (N s): geometric, 0.25 N s times 1.01^i up to 10 N s (371 actions). The
#: distance grows about like J^2, so a half step changes it by at most about 1% (1.5 cm at 1.5 m).
ACTION_IMPULSES = np.round(0.25 * 1.01 ** np.arange(0, int(np.log(40.0) / np.log(1.01)) + 1), 10)


def stop_distance(impulse: np.ndarray, mu: np.ndarray, m: np.ndarray, k_d: np.ndarray) -> np.ndarray:
    """Slide distance ``d(J)`` of the closed form above (broadcasting; ``J >= 0``).

    Written as ``tau v_c (x - ln(1 + x))`` with ``x = v0 / v_c``; below ``x = 1e-3``
    (never reached in the default prior) the series ``x^2/2 - x^3/3 + x^4/4`` replaces
    the cancelling difference, so the Coulomb limit stays exact.
    """
    impulse = np.abs(np.asarray(impulse, dtype=float))
    mu, m, k_d = (np.asarray(v, dtype=float) for v in (mu, m, k_d))
    scale = mu * G * (m / k_d) ** 2  # tau * v_c
    x = (impulse / m) / (mu * G * m / k_d)
    out = x - np.log1p(x)
    small = x < 1e-3
    if np.any(small):
        xs = np.where(small, x, 0.0)
        out = np.where(small, xs**2 / 2 - xs**3 / 3 + xs**4 / 4, out)
    return scale * out


class CoastModel(TaskModelBase):
    """A body coasting under Coulomb friction and viscous damping to a stop, aimed at a target.

    The shared part of every family whose probe and action are one scalar (an impulse,
    a release speed), whose outcome is the closed-form stop of a coast (``outcome``), and
    whose loss is the miss ``|outcome - target| / margin`` (the context is the target).
    Latent 0 is the friction, the decision coordinate. A family is a frozen dataclass
    with the fields ``sigma``, ``margin``, ``prior_low``, ``prior_high``, ``jitter_scale``
    and ``variant``, its grids, and its ``outcome(action, *latents)``.
    """

    outcome = staticmethod(stop_distance)
    #: What the context is, for the error message.
    target_name = "target distance"
    context_names = ("target",)
    binary_loss = False
    probe_dim = 1
    observation_dim = 1
    action_dim = 1

    def __post_init__(self) -> None:
        self.check_sigma_and_margin()
        if np.any(np.asarray(self.prior_low) <= 0):
            raise ValueError(f"every {self.name} latent must be positive")

    def grown_scenarios(self, particles: np.ndarray, z_points: np.ndarray) -> np.ndarray:
        """The default grown scenarios with the friction kept positive.

        A conformal threshold ``t > 1`` grows the decision interval by ``(t - 1) D`` on each
        side, which can reach below zero, where the closed form is undefined (NaN); a
        scenario there is the least friction that still slides, ``MIN_FRICTION``.
        """
        extra = super().grown_scenarios(particles, z_points)
        extra[..., 0] = np.maximum(extra[..., 0], MIN_FRICTION)
        return extra

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The coast's stop ``[E, N, 1]`` for probes ``u[E]`` (or ``[E, 1]``)."""
        theta = np.asarray(theta, dtype=float)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        return self.outcome(u, theta[..., 0], theta[..., 1], theta[..., 2])[..., None]

    def commit_outcome(self, action: np.ndarray, *latents: np.ndarray) -> np.ndarray:
        """A commit's outcome: the coast's own (a variant whose commit is another push overrides it: the hinge's
        torque of docs/decisions.md, "ex27")."""
        return self.outcome(action, *latents)

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled miss ``[E, A, N]`` (``[A, S]`` for ``theta[S, d]`` and one target)."""
        if context is None:
            raise ValueError(f"the {self.name} loss needs the {self.target_name} (context)")
        theta = np.asarray(theta, dtype=float)
        j = np.asarray(actions, dtype=float).reshape(-1)
        target = np.asarray(context, dtype=float)
        if theta.ndim == 2:
            d = self.commit_outcome(j[:, None], theta[None, :, 0], theta[None, :, 1], theta[None, :, 2])
            return np.abs(d - float(target.reshape(-1)[0])) / self.margin
        d = self.commit_outcome(j[None, :, None], theta[:, None, :, 0], theta[:, None, :, 1], theta[:, None, :, 2])
        return np.abs(d - target.reshape(-1, 1, 1)) / self.margin


@dataclass(frozen=True)
class Push1DModel(CoastModel):
    """The 1-D push task model.

    Args:
        sigma: Observation noise the likelihood assumes (m).
        margin: ``gamma``; the modeled miss is divided by it (1 = none).
        prior_low, prior_high: Box prior on ``(mu, m, k_d)``.
        variant: Label stored with every episode this model scores.
    """

    sigma: float = 0.05
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    #: About 2.5% of each prior width.
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.01, 0.025, 0.06]))
    variant: str = "deployed"

    # name, latent_names and context_names: from the declaration (probecommit.tasks.push1d).
    probe_grid = np.array(PROBE_PULSES)[:, None]
    action_grid = ACTION_IMPULSES[:, None]
    decision_domain_width = PRIOR_HIGH[0] - PRIOR_LOW[0]
