"""The simulated rig in MuJoCo: a machined pocket in a rigid block, a flat-ended tool, a touch switch.

A 2-D section extruded along y, like the insertion scene, at rig scale: a block whose
top is at z = 0 with a sharp-edged pocket of half-opening ``hg_rig(c)`` centred at
``x_hole`` and ``POCKET_DEPTH_MM`` deep. The tool is a box of half-width
``TOOL_RADIUS_MM`` (the 5.9 mm tool's section) on two slide joints. It is moved
kinematically, as the arm's position control does, in ``DESCENT_STEP_MM`` steps; after
each step MuJoCo's collision detection (``mj_fwdPosition``) says whether any contact
exists: that is the touch switch. A tap stops when the switch closes or when the tool
is ``ALLOWANCE_MM`` below the top; the commit descends to the pocket floor.

Everything is boxes, so every contact uses MuJoCo's analytic box-box collider, and each
query is a pure function of its arguments (a fresh ``qpos`` each step; bit-identical on
repeat). Compiled instances are kept per process (``compiled_rig_instance``), and a
simulator's instances share one data buffer: every step sets the whole ``qpos``, all the
state ``mj_fwdPosition`` reads, so an answer does not depend on the instance the buffer
served before (tested).
"""

from __future__ import annotations

from typing import Any

from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.engines.mujoco import DataBuffers, data_layout
from probecommit.tasks.rig.model import ALLOWANCE_MM, POCKET_DEPTH_MM, TOOL_RADIUS_MM, rig_half_gap
from probecommit.tasks.rig.sim_base import RigSimulator, descent_heights

MM = 1e-3
BLOCK_HALF_X_MM = 200.0
BLOCK_HALF_Y_MM = 40.0
FLOOR_THICKNESS_MM = 20.0
TOOL_HALF_HEIGHT_MM = 40.0
#: Contacts are reported within this distance; the switch closes at distance <= 0.
CONTACT_MARGIN_MM = 0.01
#: Compiled instances kept per process (a rig model is a few tens of kB).
MODEL_CACHE_SIZE = 128


def _f(x: float) -> str:
    return repr(float(x))


def rig_scene_xml(x_hole_mm: float, c: float) -> str:
    """MJCF of one rig instance; lengths converted to metres."""
    hg = float(rig_half_gap(c)) * MM
    xh = float(x_hole_mm) * MM
    depth = POCKET_DEPTH_MM * MM
    big = BLOCK_HALF_X_MM * MM
    hy = BLOCK_HALF_Y_MM * MM
    ft = FLOOR_THICKNESS_MM * MM
    geoms = [f'<geom name="floor" type="box" pos="0 0 {_f(-depth - ft / 2)}" size="{_f(big)} {_f(hy)} {_f(ft / 2)}"/>']
    for side, sgn in (("right", 1.0), ("left", -1.0)):
        edge, far = xh + sgn * hg, sgn * big
        geoms.append(f'<geom name="{side}" type="box" pos="{_f((edge + far) / 2)} 0 {_f(-depth / 2)}" '
                     f'size="{_f(abs(far - edge) / 2)} {_f(hy)} {_f(depth / 2)}"/>')
    r, th = TOOL_RADIUS_MM * MM, TOOL_HALF_HEIGHT_MM * MM
    return f"""
<mujoco model="rig">
  <option gravity="0 0 0"/>
  <default><geom contype="1" conaffinity="1" margin="{_f(CONTACT_MARGIN_MM * MM)}"/></default>
  <worldbody>
    {chr(10).join('    ' + g for g in geoms)}
    <body name="tool" pos="0 0 {_f(th)}">
      <inertial pos="0 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
      <joint name="tool_x" type="slide" axis="1 0 0"/>
      <joint name="tool_z" type="slide" axis="0 0 1"/>
      <geom name="tool" type="box" size="{_f(r)} {_f(r)} {_f(th)}"/>
    </body>
  </worldbody>
</mujoco>
"""


def _compile(x_hole: float, c: float) -> tuple[Any, tuple[int, ...]]:
    """Compiled model of an instance and its MjData layout (the scene depends on ``x_hole`` and ``c`` only)."""
    model = require("mujoco").MjModel.from_xml_string(rig_scene_xml(x_hole, c))
    return model, data_layout(model)


#: Compiled instances, shared by every MuJoCo rig simulator of the process (a model is never
#: modified: queries write only MjData).
compiled_rig_instance = InstanceCache(_compile, MODEL_CACHE_SIZE).get


class MujocoRigSimulator(RigSimulator):
    """The simulated rig in MuJoCo (see the module docstring)."""

    engine = "mujoco"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._mj = require("mujoco")  # lazy: importing this module never needs mujoco
        #: One MjData per memory layout, shared by every instance's model with that layout.
        self._data = DataBuffers(self._mj)

    def _touching(self, model: Any, data: Any, x_mm: float, bottom_mm: float) -> bool:
        """Whether the tool, its bottom at ``bottom_mm`` and centre at ``x_mm``, touches the block."""
        data.qpos[0] = x_mm * MM
        data.qpos[1] = bottom_mm * MM  # the body starts with its bottom at z = 0
        self._mj.mj_fwdPosition(model, data)
        return any(data.contact[i].dist <= 0.0 for i in range(data.ncon))

    def _descend(self, x_hole: float, c: float, x: float, stop: float) -> float:
        """The height (mm) where the switch closed, or ``-stop`` when it never did."""
        model, layout = compiled_rig_instance(x_hole, c)
        data = self._data.get(model, layout)
        for h in descent_heights(stop):
            if self._touching(model, data, x, float(h)):
                return float(h)
        return -float(stop)

    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        """0 on the block top, ``-ALLOWANCE_MM`` when the tap went through the opening (mm)."""
        h = self._descend(x_hole, c, u, ALLOWANCE_MM)
        return h if h > -ALLOWANCE_MM else -ALLOWANCE_MM

    def tool_depth(self, x_hole: float, c: float, a: float) -> float:
        """How far below the block top (mm, positive down) the committed tool got before it touched."""
        h = self._descend(x_hole, c, a, POCKET_DEPTH_MM + 1.0)
        return float(max(-h, 0.0))
