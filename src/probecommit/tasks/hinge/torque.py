"""The hinge's commit read as Table I's "torque": a constant torque from rest for a fixed time, then the coast.

Why: Table I gives the hinge's probe / action as "coast / torque"; the frozen family commits a release speed
(docs/decisions.md, "Hinge action = release speed"). This module is the literal reading, used only by the ex27
experiment (E182..E184; docs/decisions.md, "ex27"): the probe stays the frozen coast, the commit is a torque ``T``
the hinge motor applies for ``push_s`` seconds from rest (``push_s = 0``: an angular impulse ``J``, release speed
``J / I``). While pushed ``I dw/dt = T - f - b w`` (the door stays put if ``T <= f``), so with ``a = (T - f) / b``
and ``c = I / b`` the door leaves at ``a (1 - e^{-D / c})`` having turned ``a (D - c (1 - e^{-D / c}))``, then
coasts by the frozen closed form. Unlike a coast, the outcome needs ``I`` and ``b`` themselves, which no coast
identifies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probecommit.tasks.hinge.model import ACTION_SPEEDS, PRIOR_HIGH, PRIOR_LOW, HingeModel, inertia, stop_angle

#: Geometric step of a torque grid (1 %, as the frozen release-speed grid).
STEP = 1.01


def torque_angle(torque: np.ndarray, f: np.ndarray, b: np.ndarray, m: np.ndarray, push_s: float) -> np.ndarray:
    """Angle (rad) where a door pushed from rest by ``torque`` (N m; N m s for ``push_s = 0``) stops (broadcasting)."""
    torque, f, b = (np.asarray(v, dtype=float) for v in (torque, f, b))
    i = inertia(m)
    if push_s <= 0:  # an angular impulse: the door leaves at J / I from where it stood
        return stop_angle(torque / i, f, b, m)
    a = np.maximum(torque - f, 0.0) / b
    c = i / b
    lag = -np.expm1(-push_s / c)
    return a * (push_s - c * lag) + stop_angle(a * lag, f, b, m)


def torque_for_speed(speed: float, f: float, b: float, m: float, push_s: float) -> float:
    """The torque (impulse for ``push_s = 0``) that brings door ``(f, b, m)`` from rest to ``speed`` rad/s."""
    i = float(inertia(m))
    if push_s <= 0:
        return i * speed
    return f + b * speed / -np.expm1(-push_s * b / i)


def torque_grid(push_s: float) -> np.ndarray:
    """The declared torque grid: 1 % steps from the least torque that brings the prior box's low corner to the frozen
    grid's least release speed to the one that brings its high corner to the largest (the needed torque grows with
    each of ``f``, ``b``, ``m``, so every door of the prior reaches every frozen release speed), rounded to 1e-10."""
    lo = torque_for_speed(float(ACTION_SPEEDS[0]), *PRIOR_LOW, push_s)
    hi = torque_for_speed(float(ACTION_SPEEDS[-1]), *PRIOR_HIGH, push_s)
    count = int(np.ceil(np.log(hi / lo) / np.log(STEP))) + 1
    return np.round(lo * STEP ** np.arange(count), 10)


@dataclass(frozen=True)
class HingeTorqueModel(HingeModel):
    """The hinge model whose commit is a torque for ``push_s`` seconds (its probe stays the frozen coast).

    Built by :func:`torque_model`, which sets the class's ``action_grid`` to the duration's torque grid.
    """

    push_s: float = 0.0

    def commit_outcome(self, action: np.ndarray, f: np.ndarray, b: np.ndarray, m: np.ndarray) -> np.ndarray:
        return torque_angle(action, f, b, m, self.push_s)


def torque_model(model: HingeModel, push_s: float) -> HingeTorqueModel:
    """``model`` (its sigma, margin, prior, jitter) with the torque commit of ``push_s`` seconds and its grid."""
    cls = type(f"HingeTorque{push_s:g}s", (HingeTorqueModel,), {"action_grid": torque_grid(push_s)[:, None]})
    return cls(push_s=push_s, **{f: getattr(model, f) for f in HingeModel.__dataclass_fields__})
