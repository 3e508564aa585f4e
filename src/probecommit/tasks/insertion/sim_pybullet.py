"""PyBullet ground truth for insertion: the MuJoCo scene rebuilt box for box.

Geometry, masses, drives and the stopping rule are the MuJoCo scene's
(:mod:`probecommit.tasks.insertion.sim_mujoco`): the plate's boxes are read from that
scene's MJCF (:func:`plate_boxes`), every other number is imported from its constants.
Only the engine's own contact settings are PyBullet's
(:mod:`probecommit.engines.pybullet`), chosen for millimetre contact, never to move a
measured boundary or window (``docs/engines.md``).

* Plate: one static multibody with a compound of boxes (floor, two walls, two top slabs,
  two 45-degree chamfer boxes). PyBullet uses its exact sphere-box and box-box colliders.
* Tap: a fixed-base multibody with two prismatic links (an x carriage of negligible mass,
  then the 10 g z link carrying the 1.2 mm sphere). z is pushed down by 0.5 N with a
  2.5 N s/m damper; x is held at ``u`` by a 50 N/m spring with 1 N s/m damping. Both are
  applied as explicit joint forces every step (stable: ``b dt / m = 0.05``). Frictionless.
* Peg: the same two-link chain carrying the box peg (50 g); x spring 200 N/m, 5 N s/m;
  z driven by PyBullet's velocity motor limited to 2 N (the MuJoCo velocity servo with
  kv = 1000 N s/m, made implicit), with the same guarded approach speeds. Friction 0.3.

All public arguments and returns are in mm; PyBullet works in metres. One client per
simulator object; one plate body per instance, LRU-cached, inactive plates excluded from
collision; each query resets both probes' joints, so a query is a pure function of its
arguments (bit-identical on repeat and across objects).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any


from probecommit.engines.cache import InstanceCache

from probecommit.engines.pybullet import COLLISION_MARGIN_M  # plain constants: no pybullet import
from probecommit.tasks.insertion.model import TIP_RADIUS_MM
from probecommit.tasks.insertion.sim_base import InsertionSimulator
from probecommit.tasks.insertion.sim_mujoco import (
    CHUNK_STEPS,
    MAX_TIME_S,
    MM,
    PEG_APPROACH_SPEED,
    PEG_FAST_BELOW_MM,
    PEG_FORCE_N,
    PEG_FRICTION,
    PEG_HALF_HEIGHT_MM,
    PEG_HALF_LENGTH_MM,
    PEG_HALF_WIDTH_MM,
    PEG_INSERT_SPEED,
    PEG_LATERAL_DAMPING,
    PEG_LATERAL_STIFFNESS,
    PEG_MASS_KG,
    PEG_START_CLEARANCE_MM,
    PEG_Y_MM,
    SETTLE_CHUNKS,
    SETTLE_SPEED,
    START_CLEARANCE_MM,
    TAP_DESCENT_SPEED,
    TAP_FORCE_N,
    TAP_LATERAL_DAMPING,
    TAP_LATERAL_STIFFNESS,
    TAP_MASS_KG,
    TAP_Y_MM,
    TIMESTEP_S,
    scene_xml,
)

#: Mass (kg) of the massless-in-MuJoCo x carriage each probe chain needs in PyBullet:
#: 1% of the tap's mass, so lateral inertia is within 1% of MuJoCo's single body.
CARRIAGE_MASS_KG = 1e-4
CARRIAGE_INERTIA = 1e-9  # kg m^2; prismatic joints never rotate a link
MODEL_CACHE_SIZE = 64  # instance plates kept in one client


def plate_boxes(x_hole_mm: float, c: float) -> list[dict[str, Any]]:
    """The MuJoCo scene's plate boxes for one instance, read from its MJCF.

    Args:
        x_hole_mm: Slot centre (mm).
        c: Clearance scale.

    Returns:
        One dict per box: ``name``, ``pos`` (m, 3), ``half`` (half extents, m, 3) and
        ``quat`` (w, x, y, z).
    """
    root = ET.fromstring(scene_xml(x_hole_mm, c))
    boxes = []
    for g in root.iter("geom"):
        if g.get("class") != "plate":
            continue
        quat = [float(v) for v in g.get("quat", "1 0 0 0").split()]
        boxes.append({
            "name": g.get("name"),
            "pos": [float(v) for v in g.get("pos").split()],
            "half": [float(v) for v in g.get("size").split()],
            "quat": quat,
        })
    return boxes


class PybulletInsertionSimulator(InsertionSimulator):
    """Insertion ground truth in PyBullet (see the module docstring for the scene).

    Args:
        physics: Replaces the engine parameters (``engines.pybullet.MM_PHYSICS``; ``{}``
            is PyBullet's defaults); only for measuring what the settings do.
        collision_margin: Collision margin (m) on every body; None keeps PyBullet's
            default (only for measurements).
        plate_contact: Further ``changeDynamics`` keywords for the plate (e.g. ``contactStiffness``
            and ``contactDamping``: a compliant contact for every probe, which touches only the
            plate); None keeps the rigid contact (only for measurements, ex39's E218).
        **kwargs: ``noise_sigma``, ``aim_offset``, passed to the base class.
    """

    engine = "pybullet"

    def __init__(self, physics: dict[str, Any] | None = None, collision_margin: float | None = COLLISION_MARGIN_M,
                 plate_contact: dict[str, Any] | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._plate_contact = dict(plate_contact or {})
        from probecommit.engines import pybullet as pbe  # lazy: importing this module needs no pybullet

        self._pbe = pbe
        self._margin = collision_margin
        self._p = pbe.import_pybullet()
        self._cid: int | None = None
        self._cid = pbe.new_client(TIMESTEP_S, physics)
        self._plates = InstanceCache(self._build_plate, MODEL_CACHE_SIZE, evict=self._drop_plate)
        self._active: tuple[float, float] | None = None  # the one collidable plate: key and body
        self._active_body: int | None = None
        r = TIP_RADIUS_MM * MM
        self._tap = self._chain(
            base_z=r + START_CLEARANCE_MM * MM, y=TAP_Y_MM * MM, mass=TAP_MASS_KG, friction=0.0,
            shape=dict(shapeType=self._p.GEOM_SPHERE, radius=r))
        self._peg = self._chain(
            base_z=(PEG_HALF_HEIGHT_MM + PEG_START_CLEARANCE_MM) * MM, y=PEG_Y_MM * MM, mass=PEG_MASS_KG,
            friction=PEG_FRICTION,
            shape=dict(shapeType=self._p.GEOM_BOX,
                       halfExtents=[PEG_HALF_WIDTH_MM * MM, PEG_HALF_LENGTH_MM * MM, PEG_HALF_HEIGHT_MM * MM]))

    # ------------------------------------------------------------------ scene
    def _chain(self, base_z: float, y: float, mass: float, friction: float, shape: dict) -> dict[str, Any]:
        """A fixed-base multibody: prismatic x carriage, then a prismatic z link with the shape."""
        p, cid = self._p, self._cid
        col = p.createCollisionShape(physicsClientId=cid, **shape)
        body = p.createMultiBody(
            baseMass=0.0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=-1,
            basePosition=[0.0, y, base_z],
            linkMasses=[CARRIAGE_MASS_KG, mass], linkCollisionShapeIndices=[-1, col],
            linkVisualShapeIndices=[-1, -1], linkPositions=[[0, 0, 0], [0, 0, 0]],
            linkOrientations=[[0, 0, 0, 1]] * 2, linkInertialFramePositions=[[0, 0, 0]] * 2,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * 2, linkParentIndices=[0, 1],
            linkJointTypes=[p.JOINT_PRISMATIC] * 2, linkJointAxis=[[1, 0, 0], [0, 0, 1]],
            physicsClientId=cid)
        for link, m in ((-1, None), (0, CARRIAGE_MASS_KG), (1, mass)):
            extra = {"lateralFriction": friction}
            if m is not None:
                extra["localInertiaDiagonal"] = [CARRIAGE_INERTIA] * 3 if link == 0 else self._inertia(shape, m)
            self._pbe.mm_dynamics(body, link, cid, margin=self._margin, **extra)
        # Free the joints of PyBullet's default velocity motors; drives are set per query.
        p.setJointMotorControlArray(body, [0, 1], p.VELOCITY_CONTROL, forces=[0.0, 0.0], physicsClientId=cid)
        return {"body": body, "base_z": base_z}

    @staticmethod
    def _inertia(shape: dict, m: float) -> list[float]:
        """Solid sphere / box inertia; irrelevant to prismatic motion but kept physical."""
        if "radius" in shape:
            return [0.4 * m * shape["radius"] ** 2] * 3
        hx, hy, hz = shape["halfExtents"]
        return [m / 3 * (hy * hy + hz * hz), m / 3 * (hx * hx + hz * hz), m / 3 * (hx * hx + hy * hy)]

    def _build_plate(self, x_hole: float, c: float) -> int:
        """The instance's plate body (kept by the LRU ``self._plates``)."""
        p, cid = self._p, self._cid
        boxes = plate_boxes(x_hole, c)
        col = p.createCollisionShapeArray(
            shapeTypes=[p.GEOM_BOX] * len(boxes), halfExtents=[b["half"] for b in boxes],
            collisionFramePositions=[b["pos"] for b in boxes],
            collisionFrameOrientations=[[b["quat"][1], b["quat"][2], b["quat"][3], b["quat"][0]] for b in boxes],
            physicsClientId=cid)
        body = p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=col, baseVisualShapeIndex=-1,
                                 basePosition=[0, 0, 0], physicsClientId=cid)
        # Friction is a product in Bullet: plate 1.0 x peg 0.3 = 0.3, plate x tip 0 = 0.
        self._pbe.mm_dynamics(body, -1, cid, margin=self._margin, lateralFriction=1.0)
        if self._plate_contact:
            p.changeDynamics(body, -1, physicsClientId=cid, **self._plate_contact)
        return body

    def _drop_plate(self, key: tuple[float, float], body: int) -> None:
        self._p.removeBody(body, physicsClientId=self._cid)
        if self._active == key:
            self._active, self._active_body = None, None

    def _instance(self, x_hole: float, c: float) -> int:
        """The instance's plate body, built once (LRU-cached) and made the only collidable plate."""
        p, cid = self._p, self._cid
        key = (float(x_hole), float(c))
        body = self._plates.get(*key)
        if self._active != key:
            if self._active is not None:
                p.setCollisionFilterGroupMask(self._active_body, -1, 0, 0, physicsClientId=cid)
            p.setCollisionFilterGroupMask(body, -1, 1, 1, physicsClientId=cid)
            self._active, self._active_body = key, body
        return body

    def _reset(self) -> None:
        """Both probes back to their start pose at rest, every drive off."""
        p, cid = self._p, self._cid
        for chain in (self._tap, self._peg):
            for j in (0, 1):
                p.resetJointState(chain["body"], j, 0.0, 0.0, physicsClientId=cid)
            p.setJointMotorControlArray(chain["body"], [0, 1], p.VELOCITY_CONTROL,
                                        targetVelocities=[0.0, 0.0], forces=[0.0, 0.0], physicsClientId=cid)

    def _descend(self, chain: dict, target_x: float, kx: float, bx: float, z_control) -> tuple[float, float]:
        """Step until the driven body is in contact and both joint speeds stay settled.

        Args:
            chain: The driven probe.
            target_x: Lateral spring set point (m).
            kx, bx: Lateral spring stiffness (N/m) and damping (N s/m).
            z_control: ``z_control(qz, vz)`` run before every step; sets the z drive.

        Returns:
            Final (qx, qz) joint positions (m). Same chunked stopping rule as MuJoCo's.
        """
        p, cid, body = self._p, self._cid, chain["body"]
        quiet = 0
        max_chunks = int(round(MAX_TIME_S / (TIMESTEP_S * CHUNK_STEPS)))
        for _ in range(max_chunks):
            for _ in range(CHUNK_STEPS):
                (qx, vx, _, _), (qz, vz, _, _) = p.getJointStates(body, [0, 1], physicsClientId=cid)
                p.setJointMotorControl2(body, 0, p.TORQUE_CONTROL, force=-kx * (qx - target_x) - bx * vx,
                                        physicsClientId=cid)
                z_control(qz, vz)
                p.stepSimulation(physicsClientId=cid)
            (qx, vx, _, _), (qz, vz, _, _) = p.getJointStates(body, [0, 1], physicsClientId=cid)
            touching = len(p.getContactPoints(bodyA=body, linkIndexA=1, physicsClientId=cid)) > 0
            if touching and abs(vx) < SETTLE_SPEED and abs(vz) < SETTLE_SPEED:
                quiet += 1
                if quiet >= SETTLE_CHUNKS:
                    break
            else:
                quiet = 0
        (qx, _, _, _), (qz, _, _, _) = p.getJointStates(body, [0, 1], physicsClientId=cid)
        return qx, qz

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
        p, cid = self._p, self._cid
        self._instance(x_hole, c)
        self._reset()
        body = self._tap["body"]
        p.resetJointState(body, 0, u * MM, 0.0, physicsClientId=cid)
        damping = TAP_FORCE_N / TAP_DESCENT_SPEED

        def push(qz: float, vz: float) -> None:
            p.setJointMotorControl2(body, 1, p.TORQUE_CONTROL, force=-TAP_FORCE_N - damping * vz,
                                    physicsClientId=cid)

        _, qz = self._descend(self._tap, u * MM, TAP_LATERAL_STIFFNESS, TAP_LATERAL_DAMPING, push)
        return float((self._tap["base_z"] + qz - TIP_RADIUS_MM * MM) / MM)

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        """How far (mm, positive down) below the plate top the peg's bottom reached.

        Args:
            x_hole: Slot centre (mm).
            c: Clearance scale.
            a: Lateral aim (mm), already including any frame offset.

        Returns:
            About 15.0 when the peg reaches the pocket floor, about 0.0 when it rests on top.
        """
        p, cid = self._p, self._cid
        self._instance(x_hole, c)
        self._reset()
        body = self._peg["body"]
        p.resetJointState(body, 0, a * MM, 0.0, physicsClientId=cid)
        fast_below = -(PEG_START_CLEARANCE_MM + PEG_FAST_BELOW_MM) * MM

        def drive(qz: float, vz: float) -> None:
            # MuJoCo's guarded approach: slow until the bottom is past the chamfer.
            speed = PEG_INSERT_SPEED if qz < fast_below else PEG_APPROACH_SPEED
            p.setJointMotorControl2(body, 1, p.VELOCITY_CONTROL, targetVelocity=-speed, force=PEG_FORCE_N,
                                    physicsClientId=cid)

        _, qz = self._descend(self._peg, a * MM, PEG_LATERAL_STIFFNESS, PEG_LATERAL_DAMPING, drive)
        return float(-(self._peg["base_z"] + qz - PEG_HALF_HEIGHT_MM * MM) / MM)

    # ------------------------------------------------------------------ lifetime
    def close(self) -> None:
        """Disconnect this object's PyBullet client (idempotent)."""
        cid, self._cid = getattr(self, "_cid", None), None
        if cid is not None:
            self._pbe.disconnect(cid)

    def __del__(self) -> None:
        self.close()

    def __enter__(self) -> "PybulletInsertionSimulator":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
