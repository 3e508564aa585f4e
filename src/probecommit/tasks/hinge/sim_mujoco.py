"""Hinge ground truth in MuJoCo: a door panel on a vertical hinge with friction loss and damping.

Scene (one compiled model per truth ``(f, b, m)``, LRU-cached): a thin box door of
width ``DOOR_WIDTH_M`` (mass ``m``, its inertia about its own centre that of a uniform
panel, so ``m W^2 / 3`` about the hinge) on a hinge joint about the vertical axis with
``frictionloss = f`` (MuJoCo's dry friction: a friction constraint on the joint) and
``damping = b``; gravity is along the axis, so it exerts no torque. A coast query resets
the data, sets the joint speed and steps (implicit integration, 1 ms) until the speed
stays below ``STOP_SPEED`` for ``STOP_STEPS`` steps; it returns the joint angle.
MuJoCo's friction loss is a soft constraint (it lets the joint creep at a tiny speed
under a load below ``f``); with a stiff friction ``solref`` the coast matches the
Coulomb closed form to well under the 0.02 rad reading noise (tested).
"""

from __future__ import annotations

from typing import Any

from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.tasks.base import TargetMissSimulator
from probecommit.tasks.hinge.model import DOOR_WIDTH_M

TIMESTEP_S = 1e-3
DOOR_HEIGHT_M = 0.8
DOOR_THICKNESS_M = 0.02
STOP_SPEED = 1e-3  # rad/s
STOP_STEPS = 20
MAX_TIME_S = 30.0
#: Friction-loss constraint: a 2 ms time constant (stiff against the door's seconds-long coast).
SOLREF_FRICTION = (0.002, 1.0)
MODEL_CACHE_SIZE = 64


def _f(x: float) -> str:
    return repr(float(x))


def scene_xml(f: float, b: float, m: float) -> str:
    """MJCF of one truth ``(f, b, m)``."""
    w, h, t = DOOR_WIDTH_M, DOOR_HEIGHT_M, DOOR_THICKNESS_M
    izz = m * (w * w + t * t) / 12.0  # about the panel's centre, vertical axis
    ixx = m * (t * t + h * h) / 12.0
    iyy = m * (w * w + h * h) / 12.0
    return f"""
<mujoco model="hinge">
  <option timestep="{_f(TIMESTEP_S)}" gravity="0 0 -9.81" integrator="implicitfast"/>
  <worldbody>
    <body name="door" pos="0 0 {_f(h / 2)}">
      <joint name="hinge" type="hinge" axis="0 0 1" pos="0 0 0" frictionloss="{_f(f)}" damping="{_f(b)}"
             solreffriction="{_f(SOLREF_FRICTION[0])} {_f(SOLREF_FRICTION[1])}"/>
      <inertial pos="{_f(w / 2)} 0 0" mass="{_f(m)}" diaginertia="{_f(ixx)} {_f(iyy)} {_f(izz)}"/>
      <geom type="box" pos="{_f(w / 2)} 0 0" size="{_f(w / 2)} {_f(t / 2)} {_f(h / 2)}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


class MujocoHingeSimulator(TargetMissSimulator):
    """Hinge ground truth in MuJoCo (scene in the module docstring).

    Args:
        noise_sigma: Noise added to each stop-angle reading (rad).
    """

    engine = "mujoco"
    family = "hinge"
    query, outcome, target = "coast", "angle", "target angle"
    not_finite = "mujoco door did not stop after release at {action} rad/s"

    def __init__(self, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)
        self._mj = require("mujoco")
        self._instance = InstanceCache(self._compile, MODEL_CACHE_SIZE).get

    def _compile(self, f: float, b: float, m: float) -> tuple[Any, Any]:
        model = self._mj.MjModel.from_xml_string(scene_xml(f, b, m))
        return model, self._mj.MjData(model)

    def coast(self, f: float, b: float, m: float, speed: float) -> float:
        """Named query: the angle (rad) where the door stops after release at ``speed`` rad/s."""
        model, data = self._instance(f, b, m)
        self._mj.mj_resetData(model, data)
        data.qvel[0] = speed
        return self.settle(model, data)

    def settle(self, model: Any, data: Any) -> float:
        """Step the door as it is until it stops (its angle, rad) or ``MAX_TIME_S`` passes (NaN)."""
        mj = self._mj
        quiet = 0
        for _ in range(int(round(MAX_TIME_S / TIMESTEP_S))):
            mj.mj_step(model, data)
            quiet = quiet + 1 if abs(data.qvel[0]) < STOP_SPEED else 0
            if quiet >= STOP_STEPS:
                return float(data.qpos[0])
        return float("nan")  # never stopped: the study marks the episode failed
