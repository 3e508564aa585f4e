"""Darts ground truth in MuJoCo: a small sphere thrown with linear drag under gravity g.

Scene (one compiled model per truth ``(k_d, m, g)``, LRU-cached):

* a 1 cm radius sphere of mass ``m`` on two slide joints (x and z) starting at height
  ``RELEASE_HEIGHT`` above a ground plane at ``z = 0``; it does not collide (contype 0):
  the landing is where its centre crosses the ground plane;
* linear drag ``-k_d v`` realised as joint damping ``k_d`` on both slide joints
  (isotropic, exactly linear in velocity);
* gravity ``(0, 0, -g)`` set per truth in ``<option>``;
* RK4 integrator, timestep 1 ms (b dt <= 1e-3).

A query (an independent launch) resets the data, sets the launch velocity
``(v cos alpha, v sin alpha)`` and steps until the centre's height goes below zero; the
landing point is the linear interpolation of ``x`` between the last two steps at
``z = 0``. Deterministic, cached per ``(theta, launch)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.tasks.base import TargetMissSimulator
from probecommit.tasks.darts.model import RELEASE_HEIGHT

SPHERE_RADIUS_M = 0.01
TIMESTEP_S = 1e-3
MAX_TIME_S = 10.0
MODEL_CACHE_SIZE = 64


def _f(x: float) -> str:
    return repr(float(x))


def scene_xml(k_d: float, m: float, g: float) -> str:
    """MJCF of one truth ``(k_d, m, g)``."""
    return f"""
<mujoco model="darts">
  <option timestep="{_f(TIMESTEP_S)}" gravity="0 0 {_f(-g)}" integrator="RK4"/>
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1" contype="0" conaffinity="0"/>
    <body name="dart" pos="0 0 {_f(RELEASE_HEIGHT)}">
      <inertial pos="0 0 0" mass="{_f(m)}" diaginertia="1e-6 1e-6 1e-6"/>
      <joint name="x" type="slide" axis="1 0 0" damping="{_f(k_d)}"/>
      <joint name="z" type="slide" axis="0 0 1" damping="{_f(k_d)}"/>
      <geom name="dart" type="sphere" size="{_f(SPHERE_RADIUS_M)}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


class MujocoDartsSimulator(TargetMissSimulator):
    """Darts ground truth in MuJoCo (scene in the module docstring).

    Args:
        noise_sigma: Noise added to each landing-point reading (m).
    """

    engine = "mujoco"
    family = "darts"
    query, outcome, target = "landing", "landing", "target distance"
    not_finite = "mujoco dart did not land for launch {action}"

    def __init__(self, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)
        self._mj = require("mujoco")
        self._instance = InstanceCache(self._compile, MODEL_CACHE_SIZE).get

    def _compile(self, k_d: float, m: float, g: float) -> tuple[Any, Any]:
        model = self._mj.MjModel.from_xml_string(scene_xml(k_d, m, g))
        return model, self._mj.MjData(model)

    def landing(self, k_d: float, m: float, g: float, speed: float, elevation_deg: float) -> float:
        """Named query: ground distance (m) where a launch ``(speed, elevation)`` lands."""
        mj = self._mj
        model, data = self._instance(k_d, m, g)
        mj.mj_resetData(model, data)
        alpha = np.deg2rad(elevation_deg)
        data.qvel[0] = speed * np.cos(alpha)
        data.qvel[1] = speed * np.sin(alpha)
        x_prev, z_prev = 0.0, RELEASE_HEIGHT
        for _ in range(int(round(MAX_TIME_S / TIMESTEP_S))):
            mj.mj_step(model, data)
            x, z = float(data.qpos[0]), RELEASE_HEIGHT + float(data.qpos[1])
            if z < 0.0:
                return x_prev + (x - x_prev) * z_prev / (z_prev - z)
            x_prev, z_prev = x, z
        return float("nan")  # never landed: the study marks the episode failed
