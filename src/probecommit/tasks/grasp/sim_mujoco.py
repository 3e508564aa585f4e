"""Grasp ground truth in MuJoCo: a parallel-jaw gripper squeezing and lifting a box.

Scene (one compiled model per truth ``(mu, m)``, LRU-cached): a 4 x 4 x 8 cm box of mass
``m`` on a free joint, held in the air between two pads (1 x 3 x 6 cm) on x slide joints
of a hand body that lifts on a z slide joint. Each pad is pushed toward the box by a
motor with the grip force; the pads' own friction is zero, so every pad-box contact uses
the box's ``mu`` (MuJoCo takes the larger of the two geoms' coefficients). Elliptic
friction cones, ``impratio`` 10 and a 0.5 ms step keep Coulomb's law close (sliding
starts within a few percent of ``2 mu F = m g``; tested).

* ``squeeze(mu, m, u)``: pads at force ``u`` from rest, hand still, 50 ms; the box's drop (mm).
* ``lift(mu, m, F)``: pads at force ``F``, the hand follows ``z = a t^2 / 2`` (a stiff
  position servo) for 0.3 s; the box's slip relative to the hand (mm).

Soft contacts give a small systematic offset to a squeeze against the force balance
(about +0.6 mm when the box holds, up to +1 mm near the threshold; the reading noise is
2 mm), measured in ``docs/families.md`` and not fitted away.
"""

from __future__ import annotations

from typing import Any


from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.tasks.grasp.model import LIFT_ACCEL, SQUEEZE_S
from probecommit.tasks.grasp.sim_base import GraspSimulator

TIMESTEP_S = 5e-4
LIFT_S = 0.3
HAND_Z = 0.3
MODEL_CACHE_SIZE = 64


def _f(x: float) -> str:
    return repr(float(x))


def scene_xml(mu: float, m: float) -> str:
    """MJCF of one truth ``(mu, m)``."""
    return f"""
<mujoco model="grasp">
  <option timestep="{_f(TIMESTEP_S)}" gravity="0 0 -9.81" cone="elliptic" impratio="10"/>
  <default><geom solref="0.002 1" solimp="0.95 0.99 0.001" condim="3"/></default>
  <worldbody>
    <body name="hand" pos="0 0 {_f(HAND_Z)}">
      <joint name="lift" type="slide" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="1.0" diaginertia="1e-3 1e-3 1e-3"/>
      <body name="left" pos="-0.025 0 0">
        <joint name="left_x" type="slide" axis="1 0 0"/>
        <inertial pos="0 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
        <geom name="left_pad" type="box" size="0.005 0.015 0.03" friction="0 0 0"/>
      </body>
      <body name="right" pos="0.025 0 0">
        <joint name="right_x" type="slide" axis="1 0 0"/>
        <inertial pos="0 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
        <geom name="right_pad" type="box" size="0.005 0.015 0.03" friction="0 0 0"/>
      </body>
    </body>
    <body name="object" pos="0 0 {_f(HAND_Z)}">
      <freejoint/>
      <inertial pos="0 0 0" mass="{_f(m)}" diaginertia="1e-4 1e-4 1e-4"/>
      <geom name="object" type="box" size="0.02 0.02 0.04" friction="{_f(mu)} 0.005 0.0001"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="left_grip" joint="left_x"/>
    <motor name="right_grip" joint="right_x"/>
    <position name="hand_z" joint="lift" kp="20000" kv="400"/>
  </actuator>
</mujoco>
"""


class MujocoGraspSimulator(GraspSimulator):
    """Grasp ground truth in MuJoCo (scene in the module docstring)."""

    engine = "mujoco"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._mj = require("mujoco")
        self._instance = InstanceCache(self._compile, MODEL_CACHE_SIZE).get

    def _compile(self, mu: float, m: float) -> tuple[Any, Any, int]:
        model = self._mj.MjModel.from_xml_string(scene_xml(mu, m))
        return model, self._mj.MjData(model), model.body("object").id

    def squeeze(self, mu: float, m: float, u: float) -> float:
        """Named query: how far (mm) the box slides in 50 ms with the pads at ``u`` N."""
        mj = self._mj
        model, data, obj = self._instance(mu, m)
        mj.mj_resetData(model, data)
        data.ctrl[:] = (u, -u, 0.0)
        mj.mj_forward(model, data)
        z0 = float(data.xpos[obj, 2])
        mj.mj_step(model, data, nstep=int(round(SQUEEZE_S / TIMESTEP_S)))
        return (z0 - float(data.xpos[obj, 2])) * 1000.0

    def lift(self, mu: float, m: float, force: float) -> float:
        """Named query: the box's slip (mm) relative to the hand over a 0.3 s lift at grip ``force``."""
        mj = self._mj
        model, data, obj = self._instance(mu, m)
        mj.mj_resetData(model, data)
        data.ctrl[:] = (force, -force, 0.0)
        mj.mj_forward(model, data)
        z0 = float(data.xpos[obj, 2])
        for i in range(int(round(LIFT_S / TIMESTEP_S))):
            t = i * TIMESTEP_S
            data.ctrl[2] = 0.5 * LIFT_ACCEL * t * t
            mj.mj_step(model, data)
        hand = float(data.qpos[0])
        return (hand - (float(data.xpos[obj, 2]) - z0)) * 1000.0
