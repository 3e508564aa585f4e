"""Analytic hinge model: a door coasting on its hinge against Coulomb friction and damping (Table II).

theta = (f, b, m): Coulomb friction torque of the hinge (N m), viscous damping
(N m s/rad) and the door's mass (kg). The door is a uniform panel of width
``DOOR_WIDTH_M`` hinged at one edge about a vertical axis (gravity exerts no torque), so
its inertia about the hinge is ``I = m W^2 / 3``. Released at angular speed ``w0`` it obeys

    I dw/dt = -f - b w,    w(0) = w0 > 0,

until it stops (static friction holds it there): the same Coulomb + viscous coast as the
1-D push with ``tau = I / b`` and ``w_c = f / b``, so the stop angle is
``tau w_c (x - ln(1 + x))`` with ``x = w0 / w_c`` (:func:`stop_angle` reuses
:func:`probecommit.tasks.push1d.model.stop_distance` with that change of variables).

A probe is a coast from a known release speed (``PROBE_SPEEDS``), observing the stop
angle with ``sigma`` rad of noise; the door is returned to its start angle after each
probe. The action is the release speed the hinge motor's torque brings the door to
before letting go (a grid); the context is the target angle; the loss is the miss
``|stop angle - target|`` (rad), divided by the margin ``gamma``. Only ``I / b`` and
``f / b`` enter a coast, so ``m`` is identified only through them (as ``k_d / m`` is in
darts); a torque-impulse action would make the outcome depend on ``I`` itself, which no
coast identifies, which is why the action is a release speed (docs/decisions.md).

The decision coordinate is the friction torque ``f`` (latent 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.push1d.model import G, CoastModel, stop_distance

#: Door panel width (m): a 0.5 m cabinet-size door; I = m W^2 / 3.
DOOR_WIDTH_M = 0.5
#: Prior box on (f [N m], b [N m s/rad], m [kg]).
PRIOR_LOW = (0.2, 0.1, 2.0)
PRIOR_HIGH = (0.8, 0.5, 6.0)
#: Known release speeds of a coast probe (rad/s).
PROBE_SPEEDS = (0.5, 1.0, 1.5)
#: Commit release speeds (rad/s): 0.2 rad/s times 1.01^i up to 8 rad/s (371 actions); the
#: stop angle grows at most like w0^2, so a half step moves it by at most about 1 %.
ACTION_SPEEDS = np.round(0.2 * 1.01 ** np.arange(0, int(np.log(40.0) / np.log(1.01)) + 1), 10)


def inertia(m: np.ndarray) -> np.ndarray:
    """The door's moment of inertia about the hinge, ``m W^2 / 3`` (kg m^2)."""
    return np.asarray(m, dtype=float) * DOOR_WIDTH_M ** 2 / 3.0


def stop_angle(speed: np.ndarray, f: np.ndarray, b: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Angle (rad) where a door released at ``speed`` (rad/s) stops (broadcasting).

    The 1-D push's closed form with ``(v0, tau, v_c) = (w0, I / b, f / b)``: mass ``I``,
    damping ``b``, "friction coefficient" ``f / (g I)`` and impulse ``I w0``.
    """
    i = inertia(m)
    f = np.asarray(f, dtype=float)
    return stop_distance(i * np.abs(np.asarray(speed, dtype=float)), f / (G * i), i, np.asarray(b, dtype=float))


@dataclass(frozen=True)
class HingeModel(CoastModel):
    """The hinge task model: the shared coast model with the door's closed form.

    Args:
        sigma: Observation noise the likelihood assumes (rad).
        margin: ``gamma``; the modeled miss is divided by it (1 = none).
        prior_low, prior_high: Box prior on ``(f, b, m)``.
        variant: Label stored with every episode this model scores.
    """

    sigma: float = 0.02
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    #: About 2.5 % of each prior width.
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.015, 0.01, 0.1]))
    variant: str = "deployed"

    # name, latent_names and context_names: from the declaration (probecommit.tasks.hinge).
    outcome = staticmethod(stop_angle)
    target_name = "target angle"
    probe_grid = np.array(PROBE_SPEEDS)[:, None]
    action_grid = ACTION_SPEEDS[:, None]
    decision_domain_width = PRIOR_HIGH[0] - PRIOR_LOW[0]
    #: Stop angles a coast can physically read (rad): the door swings at most half a turn here.
    observation_range = (-0.2, 3.5)
