"""MuJoCo ground truth for insertion: a chamfered slot, a sprung tap probe and a sprung peg.

The scene is a 2-D section extruded along y (the slot runs the full plate length):
a plate whose top is at z = 0 with a slot of half-gap ``hg(c) = 4 + 0.6 c`` mm centred
at ``x_hole``, 15 mm deep, whose two top edges are cut by 45-degree chamfers of width
``CHAMFER_MM``. Everything is built from boxes, so every contact uses MuJoCo's
analytic sphere-box and box-box colliders (no mesh, no GJK).

* The tap probe is a 1.2 mm sphere on two slide joints: z is pushed down by a constant
  0.5 N with a damper that caps the descent speed; x is held at ``u`` by a soft spring
  (a position servo). The tip-plate contact is frictionless, so a tip that lands on the
  chamfer, or on its outer edge, slides into the slot and reads the floor. The flip
  from pocket to top therefore sits at the chamfer's outer edge, ``hg + CHAMFER_MM``.
* The peg is a box of half-width ``PEG_HALF_WIDTH_MM`` on the same two joints, driven
  down by a force-limited velocity servo (a slow guarded approach near the plate top,
  fast below the chamfer), with a stiffer lateral spring and friction. Its bottom
  corner slides down the chamfer when it lands there, so it enters while
  ``|a - x_hole| < hg + CHAMFER_MM - PEG_HALF_WIDTH_MM = 0.6 c + 1.1`` mm.

All public arguments and returns are in mm; MuJoCo works in metres. A compiled model is
cached per instance ``(x_hole, c)`` (one LRU for the process) and a simulator keeps one
MjData for every instance; each query resets the data, so a query is a pure function of
its arguments (bit-identical on repeat, and whatever the data served before). See ``docs/decisions.md``,
"MuJoCo insertion scene", for every parameter and why.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.engines.mujoco import DataBuffers, data_layout
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, POCKET_DEPTH_MM, TIP_RADIUS_MM, half_gap
from probecommit.tasks.insertion.sim_base import InsertionSimulator

MM = 1e-3  # metres per mm

# --- Scene parameters (mm unless stated); see docs/decisions.md -------------------------
#: 45-degree chamfer width at each slot edge; the tap flip sits at its outer edge.
CHAMFER_MM = PAPER_DELTA_MM  # the paper reports its MuJoCo scan at hg + 0.905 mm
#: Peg half-width; capture half-width is hg + chamfer - this = 0.6 c + 1.1 mm.
PEG_HALF_WIDTH_MM = 4.0 + CHAMFER_MM - 1.1
PEG_HALF_LENGTH_MM = 5.0  # along the slot (y)
PEG_HALF_HEIGHT_MM = 10.0
PLATE_HALF_X_MM = 60.0
PLATE_HALF_Y_MM = 40.0
FLOOR_THICKNESS_MM = 10.0
TAP_Y_MM = -20.0  # the tap and the peg use different stretches of the slot
PEG_Y_MM = 20.0
START_CLEARANCE_MM = 1.0  # tap tip's lowest point above the plate top at t = 0
PEG_START_CLEARANCE_MM = 0.2  # the peg starts close: its approach is slow

TIMESTEP_S = 2e-4
SOLREF = (0.002, 1.0)  # stiff contact: 2 ms time constant, critically damped
SOLIMP = (0.95, 0.99, 0.001)

TAP_MASS_KG = 0.01
TAP_FORCE_N = 0.5
TAP_DESCENT_SPEED = 0.2  # m/s terminal speed = force / damping
TAP_LATERAL_STIFFNESS = 50.0  # N/m, soft: well below 0.5 N / r = 417 N/m
TAP_LATERAL_DAMPING = 1.0  # N s/m, about 0.7 of critical

PEG_MASS_KG = 0.05
PEG_FORCE_N = 2.0  # force limit of the peg's vertical velocity servo
PEG_SERVO_GAIN = 1000.0  # N s/m: saturates at PEG_FORCE_N once the peg is 2 mm/s slow
PEG_APPROACH_SPEED = 0.01  # m/s guarded approach while the bottom is near the plate top
PEG_INSERT_SPEED = 0.2  # m/s once the bottom is below the chamfer
PEG_FAST_BELOW_MM = 2.0  # switch depth: bottom this far below the plate top
PEG_LATERAL_STIFFNESS = 200.0
PEG_LATERAL_DAMPING = 5.0  # about 0.8 of critical
PEG_FRICTION = 0.3

# --- Stopping rule ----------------------------------------------------------------------
CHUNK_STEPS = 10  # steps per mj_step call between stop checks (2 ms)
SETTLE_SPEED = 1e-4  # m/s: both joint speeds below this ...
SETTLE_CHUNKS = 3  # ... for this many consecutive chunks, with contact, means stopped
MAX_TIME_S = 0.5

MODEL_CACHE_SIZE = 64  # compiled instances kept per process (0.3 MB each; a rebuild costs ~5 ms, queries are cached above)


def _f(x: float) -> str:
    """Format a float for MJCF so it round-trips exactly (repr is shortest round-trip)."""
    return repr(float(x))


def _box(name: str, cx: float, cz: float, hx: float, hy: float, hz: float, quat: str | None = None) -> str:
    q = f' quat="{quat}"' if quat else ""
    return (
        f'<geom name="{name}" class="plate" type="box" pos="{_f(cx)} 0 {_f(cz)}"'
        f' size="{_f(hx)} {_f(hy)} {_f(hz)}"{q}/>'
    )


def scene_xml(x_hole_mm: float, c: float) -> str:
    """MJCF for one instance ``(x_hole, c)``; all lengths converted to metres.

    Args:
        x_hole_mm: Slot centre (mm).
        c: Clearance scale; the slot half-gap is ``4 + 0.6 c`` mm.

    Returns:
        The MJCF string.
    """
    hg = float(half_gap(c)) * MM
    xh = float(x_hole_mm) * MM
    ch = CHAMFER_MM * MM
    depth = POCKET_DEPTH_MM * MM
    big = PLATE_HALF_X_MM * MM
    hy = PLATE_HALF_Y_MM * MM
    floor_t = FLOOR_THICKNESS_MM * MM
    geoms = [_box("floor", 0.0, -depth - floor_t / 2, big, hy, floor_t / 2)]
    s2 = np.sqrt(0.5)
    for side, sgn in (("right", 1.0), ("left", -1.0)):
        edge = xh + sgn * hg  # wall face
        outer = edge + sgn * ch  # chamfer's outer edge on the plate top
        far = sgn * big
        # Wall below the chamfer, from the slot face out to the plate end.
        geoms.append(_box(f"{side}_wall", (edge + far) / 2, (-depth - ch) / 2, abs(far - edge) / 2, hy, (depth - ch) / 2))
        # Top layer (z in [-ch, 0]) from the chamfer's outer edge outward.
        geoms.append(_box(f"{side}_top", (outer + far) / 2, -ch / 2, abs(far - outer) / 2, hy, ch / 2))
        # Chamfer: a box turned 45 degrees about y whose outer face is the chamfer plane;
        # its face spans exactly the chamfer and its body lies inside the wall and top boxes.
        half_len = ch * s2  # half of the face length ch*sqrt(2)
        half_thk = ch * s2 / 2
        cx = xh + sgn * (hg + 0.75 * ch)
        cz = -0.75 * ch
        theta = -sgn * np.pi / 4  # right: -45 deg maps local x to (1, 0, 1)/sqrt(2)
        quat = f"{_f(np.cos(theta / 2))} 0 {_f(np.sin(theta / 2))} 0"
        geoms.append(_box(f"{side}_chamfer", cx, cz, half_len, hy, half_thk, quat))

    r = TIP_RADIUS_MM * MM
    clear = START_CLEARANCE_MM * MM
    pw, pl, ph = PEG_HALF_WIDTH_MM * MM, PEG_HALF_LENGTH_MM * MM, PEG_HALF_HEIGHT_MM * MM
    tap_damping = TAP_FORCE_N / TAP_DESCENT_SPEED
    sr = f"{_f(SOLREF[0])} {_f(SOLREF[1])}"
    si = " ".join(_f(v) for v in SOLIMP)
    return f"""
<mujoco model="insertion">
  <size memory="1M"/>
  <option timestep="{_f(TIMESTEP_S)}" gravity="0 0 0" integrator="implicitfast"/>
  <default>
    <geom solref="{sr}" solimp="{si}"/>
    <default class="plate">
      <!-- condim 1 (frictionless) here and on the tip; the peg's condim 3 wins its pairs. -->
      <geom condim="1" contype="2" conaffinity="1" friction="{_f(PEG_FRICTION)} 0.005 0.0001"/>
    </default>
  </default>
  <worldbody>
    {chr(10).join('    ' + g for g in geoms)}
    <body name="tap" pos="0 {_f(TAP_Y_MM * MM)} {_f(r + clear)}">
      <inertial pos="0 0 0" mass="{_f(TAP_MASS_KG)}" diaginertia="1e-6 1e-6 1e-6"/>
      <joint name="tap_x" type="slide" axis="1 0 0" damping="{_f(TAP_LATERAL_DAMPING)}"/>
      <joint name="tap_z" type="slide" axis="0 0 1" damping="{_f(tap_damping)}"/>
      <geom name="tip" type="sphere" size="{_f(r)}" condim="1" contype="1" conaffinity="2"/>
    </body>
    <body name="peg" pos="0 {_f(PEG_Y_MM * MM)} {_f(ph + PEG_START_CLEARANCE_MM * MM)}">
      <inertial pos="0 0 0" mass="{_f(PEG_MASS_KG)}" diaginertia="1e-5 1e-5 1e-5"/>
      <joint name="peg_x" type="slide" axis="1 0 0" damping="{_f(PEG_LATERAL_DAMPING)}"/>
      <joint name="peg_z" type="slide" axis="0 0 1"/>
      <geom name="peg" type="box" size="{_f(pw)} {_f(pl)} {_f(ph)}" condim="3" contype="1" conaffinity="2"
            friction="{_f(PEG_FRICTION)} 0.005 0.0001"/>
    </body>
  </worldbody>
  <actuator>
    <position name="tap_x_spring" joint="tap_x" kp="{_f(TAP_LATERAL_STIFFNESS)}"/>
    <motor name="tap_push" joint="tap_z"/>
    <position name="peg_x_spring" joint="peg_x" kp="{_f(PEG_LATERAL_STIFFNESS)}"/>
    <velocity name="peg_push" joint="peg_z" kv="{_f(PEG_SERVO_GAIN)}" forcelimited="true"
              forcerange="{_f(-PEG_FORCE_N)} {_f(PEG_FORCE_N)}"/>
  </actuator>
</mujoco>
"""


def _compile(x_hole: float, c: float) -> tuple[Any, dict[str, int], tuple[int, ...]]:
    """Compiled model, named indices and MjData layout of an instance (the scene depends on
    ``x_hole`` and ``c`` only). The layout is the model's integer size fields (``nq``,
    ``nbody``, ...), which fix the size and arrangement of an MjData's buffers."""
    mj = require("mujoco")
    model = mj.MjModel.from_xml_string(scene_xml(x_hole, c))
    idx = {
        "tap_x": model.jnt_qposadr[mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, "tap_x")],
        "tap_z": model.jnt_qposadr[mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, "tap_z")],
        "peg_x": model.jnt_qposadr[mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, "peg_x")],
        "peg_z": model.jnt_qposadr[mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, "peg_z")],
        "tip": mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, "tip"),
        "peg": mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, "peg"),
        "tap_x_spring": mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, "tap_x_spring"),
        "tap_push": mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, "tap_push"),
        "peg_x_spring": mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, "peg_x_spring"),
        "peg_push": mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, "peg_push"),
    }
    return model, idx, data_layout(model)


#: Compiled instances, shared by every MuJoCo insertion simulator of the process: a model is
#: a pure function of (x_hole, c) and is never modified (queries write only MjData), so runs,
#: replays and calibrations of the same instances compile each once while it stays cached.
compiled_instance = InstanceCache(_compile, MODEL_CACHE_SIZE).get


class MujocoInsertionSimulator(InsertionSimulator):
    """Insertion ground truth in MuJoCo (see the module docstring for the scene).

    Args:
        noise_sigma: Tap noise the simulator adds (mm), passed to the base class.
        aim_offset: Simulator-side aim offset (frame fault, mm), passed to the base class.
    """

    engine = "mujoco"
    # MuJoCo releases the GIL in mj_step; a thread's queries use that thread's MjData.
    parallel_queries = True
    thread_safe = True  # buffers per thread, compiled instances behind a lock

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._mj = require("mujoco")  # lazy: importing this module never needs mujoco
        #: One MjData per memory layout, shared by every instance's model with that layout.
        self._data = DataBuffers(self._mj)

    # ------------------------------------------------------------------ model cache
    def _instance(self, x_hole: float, c: float) -> tuple[Any, Any, dict[str, int]]:
        """(model, data, indices) of an instance: its compiled model (from the process-wide LRU
        ``compiled_instance``) and a data buffer this simulator shares across instances. Every
        query resets the data first (``mj_resetData``), so an answer does not depend on the
        instance the buffer served before (tested)."""
        model, idx, layout = compiled_instance(x_hole, c)
        return model, self._data.get(model, layout), idx

    def _descend(self, model: Any, data: Any, jx: int, jz: int, schedule: Any = None) -> None:
        """Step until the driven body is in contact and both its joint speeds stay settled.

        Args:
            model, data: The instance's model and freshly reset data.
            jx, jz: qpos/qvel addresses of the driven body's lateral and vertical joints.
            schedule: Optional callable ``schedule(data)`` run before every chunk (sets ctrl).

        Stops in whole chunks of ``CHUNK_STEPS``, so the stopping step, and hence the
        result, is a deterministic function of the query.
        """
        mj = self._mj
        quiet = 0
        max_chunks = int(round(MAX_TIME_S / (TIMESTEP_S * CHUNK_STEPS)))
        for _ in range(max_chunks):
            if schedule is not None:
                schedule(data)
            mj.mj_step(model, data, nstep=CHUNK_STEPS)
            vx, vz = data.qvel[jx], data.qvel[jz]
            if data.ncon > 0 and abs(vx) < SETTLE_SPEED and abs(vz) < SETTLE_SPEED:
                quiet += 1
                if quiet >= SETTLE_CHUNKS:
                    return
            else:
                quiet = 0

    # ------------------------------------------------------------------ named queries
    def tap_reading(self, x_hole: float, c: float, u: float) -> float:
        """Height (mm) of the tip's lowest point where the tap stops, relative to the plate top.

        Args:
            x_hole: Slot centre (mm).
            c: Clearance scale.
            u: Lateral tap position (mm).

        Returns:
            About 0.0 on the plate top, about -15.0 on the pocket floor.
        """
        model, data, idx = self._instance(x_hole, c)
        mj = self._mj
        mj.mj_resetData(model, data)
        data.qpos[idx["tap_x"]] = u * MM
        data.ctrl[idx["tap_x_spring"]] = u * MM
        data.ctrl[idx["tap_push"]] = -TAP_FORCE_N
        self._descend(model, data, idx["tap_x"], idx["tap_z"])
        mj.mj_kinematics(model, data)
        tip_low = data.geom_xpos[idx["tip"], 2] - model.geom_size[idx["tip"], 0]
        return float(tip_low / MM)

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        """How far (mm, positive down) below the plate top the peg's bottom reached.

        Args:
            x_hole: Slot centre (mm).
            c: Clearance scale.
            a: Lateral aim (mm), already including any frame offset.

        Returns:
            About 15.0 when the peg reaches the pocket floor, about 0.0 when it rests on top.
        """
        model, data, idx = self._instance(x_hole, c)
        mj = self._mj
        mj.mj_resetData(model, data)
        data.qpos[idx["peg_x"]] = a * MM
        data.ctrl[idx["peg_x_spring"]] = a * MM
        jz, act = idx["peg_z"], idx["peg_push"]
        # qpos of peg_z is the bottom's displacement from its start height.
        fast_below = -(PEG_START_CLEARANCE_MM + PEG_FAST_BELOW_MM) * MM

        def schedule(d: Any) -> None:
            # Guarded approach: slow while the bottom can touch the top or the chamfer, so the
            # contact's transient sink (about speed x 2 ms) cannot hook the chamfer's top edge.
            d.ctrl[act] = -(PEG_INSERT_SPEED if d.qpos[jz] < fast_below else PEG_APPROACH_SPEED)

        self._descend(model, data, idx["peg_x"], jz, schedule)
        mj.mj_kinematics(model, data)
        bottom = data.geom_xpos[idx["peg"], 2] - model.geom_size[idx["peg"], 2]
        return float(-bottom / MM)
