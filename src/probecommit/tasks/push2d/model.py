"""Analytic 2-D push model: a box on a plane struck by a 2-D impulse (paper Table II).

theta = (mu, m, k_d) as in the 1-D push. An impulse ``J = (J_x, J_y)`` (N s) through the
box's centre of mass sends it straight along ``J / |J|`` (isotropic Coulomb friction,
isotropic linear damping, no rotation); it stops after the 1-D closed-form distance
(:func:`probecommit.tasks.push1d.model.stop_distance`)

    d(|J|) = tau [v0 - v_c ln(1 + v0 / v_c)],  v0 = |J| / m, tau = m / k_d,
    v_c = kappa mu g m / k_d,

with one fitted constant ``kappa`` (``mu_scale``), the effective-friction correction
fitted to the MuJoCo scene on development truths before any audit (see
:func:`probecommit.tasks.push2d.sim_mujoco.fit_friction_scale`). The engine is the
truth; this model is what the belief and the executors use.

A probe is a known pulse of magnitude ``u`` along +x; it observes the 2-D rest
position (``sigma`` metres per component). The action is a 2-D impulse on a polar grid
(bearing x magnitude), stored as ``(J_x, J_y)``; the context is the 2-D target; the loss
is the miss ``||rest(J) - target||`` divided by the margin ``gamma``.

The decision coordinate is ``mu`` (latent 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.base import TaskModelBase
from probecommit.tasks.push1d.model import PRIOR_HIGH, PRIOR_LOW, PROBE_PULSES, stop_distance

#: Commit bearings (deg): -30 to 40 in 5-degree steps (15); both target bearings are on it.
ACTION_BEARINGS_DEG = np.arange(-30.0, 40.0 + 1e-9, 5.0)
#: Commit magnitudes (N s): 0.25 * 1.02^i up to 10 N s (187); a half step moves the rest
#: point by at most about 2% of its distance.
ACTION_MAGNITUDES = np.round(0.25 * 1.02 ** np.arange(0, int(np.log(40.0) / np.log(1.02)) + 1), 10)


#: ``kappa`` fitted by ``sim_mujoco.fit_friction_scale`` on the development truths
#: ``FIT_TRUTHS`` x pulses {1, 2, 3} N s (6 noise-free engine readings): 1.00194, rounded.
#: RMS model-engine slide error 0.49 mm at kappa = 1, 0.07 mm at the fit.
FITTED_MU_SCALE = 1.0019


def polar_grid(bearings_deg: np.ndarray, magnitudes: np.ndarray) -> np.ndarray:
    """``[B * M, 2]`` impulses, bearing-major."""
    b = np.deg2rad(np.asarray(bearings_deg, dtype=float))[:, None]
    mag = np.asarray(magnitudes, dtype=float)[None, :]
    return np.stack([(mag * np.cos(b)).ravel(), (mag * np.sin(b)).ravel()], axis=-1)


def rest_position(impulse: np.ndarray, mu: np.ndarray, m: np.ndarray, k_d: np.ndarray, mu_scale: float = 1.0) -> np.ndarray:
    """Rest position ``[..., 2]`` of a box struck from the origin with ``impulse[..., 2]``."""
    impulse = np.asarray(impulse, dtype=float)
    mag = np.hypot(impulse[..., 0], impulse[..., 1])
    d = stop_distance(mag, mu_scale * np.asarray(mu, dtype=float), m, k_d)
    safe = np.where(mag > 0, mag, 1.0)
    return np.stack([d * impulse[..., 0] / safe, d * impulse[..., 1] / safe], axis=-1)


@dataclass(frozen=True)
class Push2DModel(TaskModelBase):
    """The 2-D push task model.

    Args:
        sigma: Observation noise per component the likelihood assumes (m).
        margin: ``gamma``; the modeled miss is divided by it (1 = none).
        mu_scale: Fitted effective-friction factor ``kappa`` (1 = the nominal closed form).
        prior_low, prior_high: Box prior on ``(mu, m, k_d)``.
        variant: Label stored with every episode this model scores.
    """

    sigma: float = 0.05
    margin: float = 1.0
    mu_scale: float = FITTED_MU_SCALE
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.01, 0.025, 0.06]))
    variant: str = "deployed"

    # name, latent_names and context_names: from the declaration (probecommit.tasks.push2d).
    probe_grid = np.array(PROBE_PULSES)[:, None]
    action_grid = polar_grid(ACTION_BEARINGS_DEG, ACTION_MAGNITUDES)
    binary_loss = False
    decision_domain_width = PRIOR_HIGH[0] - PRIOR_LOW[0]
    probe_dim = 1
    observation_dim = 2
    action_dim = 2

    def __post_init__(self) -> None:
        self.check_sigma_and_margin()
        if not (np.isfinite(self.mu_scale) and self.mu_scale > 0):
            raise ValueError(f"mu_scale must be positive, got {self.mu_scale!r}")

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Rest position ``[E, N, 2]`` of a pulse of magnitude ``u[E]`` along +x."""
        theta = np.asarray(theta, dtype=float)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        d = stop_distance(u, self.mu_scale * theta[..., 0], theta[..., 1], theta[..., 2])
        return np.stack([d, np.zeros_like(d)], axis=-1)

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled miss ``[E, A, N]`` (``[A, S]`` for ``theta[S, d]`` and one target).

        Uses ``||d e - t||^2 = d^2 + |t|^2 - 2 d (e . t)`` with the unit direction ``e`` of
        each action: the distance is computed once per action magnitude and particle.
        """
        if context is None:
            raise ValueError("the push2d loss needs the 2-D target (context)")
        theta = np.asarray(theta, dtype=float)
        actions = np.asarray(actions, dtype=float).reshape(-1, 2)
        target = np.asarray(context, dtype=float)
        mag = np.hypot(actions[:, 0], actions[:, 1])
        unit = actions / np.where(mag > 0, mag, 1.0)[:, None]
        mags, inverse = np.unique(mag, return_inverse=True)
        if theta.ndim == 2:
            t = target.reshape(2)
            d = stop_distance(mags[:, None], self.mu_scale * theta[None, :, 0], theta[None, :, 1], theta[None, :, 2])[inverse]
            along = (unit @ t)[:, None]  # [A, 1]
            return self._miss(d, float(t @ t), along)
        t = target.reshape(-1, 2)  # [E, 2]
        d = stop_distance(mags[None, :, None], self.mu_scale * theta[:, None, :, 0], theta[:, None, :, 1], theta[:, None, :, 2])
        d = d[:, inverse, :]  # [E, A, N]
        along = (t @ unit.T)[:, :, None]  # [E, A, 1]
        return self._miss(d, np.sum(t * t, axis=1)[:, None, None], along)

    def _miss(self, d: np.ndarray, t_sq: float | np.ndarray, along: np.ndarray) -> np.ndarray:
        """``sqrt(max(d^2 + |t|^2 - 2 d (e . t), 0)) / margin``, in place in two arrays of ``d``'s size
        (``d`` is overwritten): the same operations in the same order as the expression, bit for bit,
        without its four temporaries ([E, A, N] is 138 MB for one push2d unit)."""
        sq = d * d
        sq += t_sq
        d *= 2.0
        d *= along
        sq -= d
        del d
        np.maximum(sq, 0.0, out=sq)
        np.sqrt(sq, out=sq)
        sq /= self.margin
        return sq
