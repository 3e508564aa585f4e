"""Analytic planar-slide model: a puck struck across a table, aimed at a target.

A small continuous-loss family that exercises every general shape of the contract:
a 3-D latent, a vector observation, a 2-D action and a per-episode context.

theta = (mu, phi, m): Coulomb friction coefficient, heading bias of the table (rad; the
puck leaves at the impulse's angle plus ``phi``) and mass (kg). An impulse ``J`` (N s,
a 2-vector) gives the puck speed ``|J| / m``; it slides ``d = |J|^2 / (2 g mu m^2)``
metres along the rotated direction. A probe strikes with a known magnitude along +x and
observes the 2-D rest position (``sigma`` metres of noise per component). The action is
an impulse on a grid; the context is the target's position; the loss is the miss
distance ``||rest(J, theta) - target||``. ``mu`` and ``m`` enter only through
``mu m^2``, so they are not separately identifiable: the decision coordinate is ``mu``
all the same, a deliberate weak spot for the audit to see.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.base import TaskModelBase

G = 9.81
#: Prior box on (mu, phi [rad], m [kg]).
PRIOR_LOW = (0.2, -0.2, 0.5)
PRIOR_HIGH = (0.6, 0.2, 1.5)


def rest_position(impulse: np.ndarray, mu: np.ndarray, phi: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Rest position ``[..., 2]`` of a puck struck with ``impulse[..., 2]`` from the origin."""
    jx, jy = impulse[..., 0], impulse[..., 1]
    distance = (jx**2 + jy**2) / (2.0 * G * mu * m**2)
    heading = np.arctan2(jy, jx) + phi
    return np.stack([distance * np.cos(heading), distance * np.sin(heading)], axis=-1)


@dataclass(frozen=True)
class PlanarSlideModel(TaskModelBase):
    """The planar-slide task model.

    Args:
        sigma: Observation noise per component the likelihood assumes (m).
        margin: ``gamma``; the modeled miss is divided by it (1 = none).
        prior_low, prior_high: Box prior on ``(mu, phi, m)``.
        variant: Label stored with every episode this model scores.
    """

    sigma: float = 0.02
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.01, 0.005, 0.02]))
    variant: str = "deployed"

    # name, latent_names and context_names: from the declaration (probecommit.tasks.planar_slide).
    probe_grid = np.array([[1.0], [2.0], [3.0]])
    action_grid = np.stack(
        np.meshgrid(np.linspace(0.5, 4.0, 15), np.linspace(-1.5, 1.5, 13), indexing="ij"), axis=-1
    ).reshape(-1, 2)
    binary_loss = False
    decision_domain_width = 0.4
    probe_dim = 1
    observation_dim = 2
    action_dim = 2

    def __post_init__(self) -> None:
        self.check_sigma_and_margin()

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Rest position ``[E, N, 2]`` of a strike of magnitude ``u[E, 1]`` along +x."""
        theta = np.asarray(theta, dtype=float)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        impulse = np.stack([np.broadcast_to(u, theta.shape[:2]), np.zeros(theta.shape[:2])], axis=-1)
        return rest_position(impulse, theta[..., 0], theta[..., 1], theta[..., 2])

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled miss ``[E, A, N]`` (``[A, S]`` for ``theta[S, d]``) to the context's target."""
        if context is None:
            raise ValueError("the planar_slide loss needs the target (context)")
        theta = np.asarray(theta, dtype=float)
        actions = np.asarray(actions, dtype=float)
        target = np.asarray(context, dtype=float)
        if theta.ndim == 2:  # a prior sample [S, d] with one target [2] or [1, 2]
            rest = rest_position(actions[:, None, :], theta[None, :, 0], theta[None, :, 1], theta[None, :, 2])
            return np.linalg.norm(rest - target.reshape(1, 1, 2), axis=-1) / self.margin
        rest = rest_position(actions[None, :, None, :], theta[:, None, :, 0], theta[:, None, :, 1], theta[:, None, :, 2])
        return np.linalg.norm(rest - target[:, None, None, :], axis=-1) / self.margin
