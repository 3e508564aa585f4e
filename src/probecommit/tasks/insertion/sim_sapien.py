"""SAPIEN 3 (PhysX) ground truth for insertion: the MuJoCo scene rebuilt box for box.

Geometry, masses, drives and the stopping rule are the MuJoCo scene's
(:mod:`probecommit.tasks.insertion.sim_mujoco`): the plate's boxes are the MuJoCo MJCF's
(:func:`~probecommit.tasks.insertion.sim_pybullet.plate_boxes`), every other number is
imported from its constants. Only PhysX's own settings are chosen here
(:mod:`probecommit.engines.sapien`), for millimetre contact, never to move a measured
boundary or window (``docs/engines.md``).

* Plate: one static actor of boxes, split at y = 0 into the tap's stretch (y < 0,
  frictionless material) and the peg's (y > 0, friction 0.3), because PhysX averages
  the two materials' friction and SAPIEN exposes no combine mode; the probes work 20 mm
  from the seam. Collision shapes only: no visual, no ground.
* Tap and peg: each a fixed-root articulation with two prismatic joints (an x carriage of
  negligible mass, then the z link carrying the 1.2 mm sphere or the box peg). PhysX
  joint drives are implicit spring-dampers ``F = k (q* - q) + b (v* - v)``, which express
  MuJoCo's actuators exactly: tap z is ``k = 0, b = 2.5 N s/m, v* = -0.2 m/s`` (0.5 N
  push at rest, 0.2 m/s terminal speed); peg z is ``k = 0, b = 1000 N s/m`` limited to
  2 N with the guarded approach's ``v*``; the lateral springs are ``k = 50 / 200 N/m``,
  ``b = 1 / 5 N s/m``.

All public arguments and returns are in mm; PhysX works in metres (single precision).
One PhysX scene per instance, LRU-cached; each query resets both articulations' joint
state and drive targets, so a query is a pure function of its arguments.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.engines.cache import InstanceCache

from probecommit.tasks.insertion.model import POCKET_DEPTH_MM, TIP_RADIUS_MM, half_gap
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
    PEG_SERVO_GAIN,
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
)
from probecommit.tasks.insertion.sim_mujoco import CHAMFER_MM, PLATE_HALF_X_MM
from probecommit.tasks.insertion.sim_pybullet import CARRIAGE_INERTIA, CARRIAGE_MASS_KG, plate_boxes

MODEL_CACHE_SIZE = 64  # PhysX scenes kept (one per instance)
#: Quaternion (w, x, y, z) turning a joint frame's x axis (PhysX's prismatic axis) onto z.
_X_TO_Z = (float(np.sqrt(0.5)), 0.0, -float(np.sqrt(0.5)), 0.0)


def plate_prisms(x_hole_mm: float, c: float, half_y: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each slot side's wall, top slab and chamfer as one convex prism (same surface as the boxes).

    A side's cross-section (x, z), the wall up to the chamfer, the top slab and the 45-degree
    chamfer cut, is the convex pentagon ``(edge, -depth), (far, -depth), (far, 0),
    (edge + ch, 0), (edge, -ch)``, so it is one convex hull with no internal seam; the MuJoCo
    boxes' union has exactly this surface. Extruded over ``+-half_y``.

    Args:
        x_hole_mm: Slot centre (mm).
        c: Clearance scale.
        half_y: Half the extrusion length (m).

    Returns:
        Per side, ``(centre, vertices)``: the prism's local origin (m, in the plate frame)
        and its 10 vertices relative to it (m). Local coordinates keep float32 exact to ~1 nm.
    """
    hg, xh, ch = float(half_gap(c)) * MM, float(x_hole_mm) * MM, CHAMFER_MM * MM
    depth, far_x = POCKET_DEPTH_MM * MM, PLATE_HALF_X_MM * MM
    out = []
    for sgn in (-1.0, 1.0):
        edge = xh + sgn * hg
        section = [(edge, -depth), (sgn * far_x, -depth), (sgn * far_x, 0.0), (edge + sgn * ch, 0.0), (edge, -ch)]
        centre = np.array([0.5 * (edge + sgn * far_x), 0.0, -0.5 * depth])
        verts = np.array([[x - centre[0], y, z - centre[2]] for x, z in section for y in (-half_y, half_y)])
        out.append((centre, verts))
    return out


class SapienInsertionSimulator(InsertionSimulator):
    """Insertion ground truth in SAPIEN 3 / PhysX (see the module docstring for the scene).

    Args:
        scene_config, body, shape: Overrides of ``engines.sapien.MM_SCENE``, ``MM_BODY``,
            ``MM_SHAPE``; only for measuring what the settings do, never in a study.
        plate: ``"prisms"`` (default: each side one convex prism, no internal seam) or
            ``"boxes"`` (MuJoCo's seven boxes; PhysX snags a peg corner on the chamfer/wall
            seam there, see docs/engines.md). Both have the same surface.
        **kwargs: ``noise_sigma``, ``aim_offset``, passed to the base class.
    """

    engine = "sapien"

    def __init__(self, scene_config: dict[str, Any] | None = None, body: dict[str, Any] | None = None,
                 shape: dict[str, float] | None = None, plate: str = "prisms", **kwargs: Any) -> None:
        super().__init__(**kwargs)
        if plate not in ("prisms", "boxes"):
            raise ValueError(f"plate must be 'prisms' or 'boxes', got {plate!r}")
        self.plate = plate
        from probecommit.engines import sapien as se  # lazy: importing this module needs no sapien

        self._se = se
        self._sapien = se.import_sapien()
        self._overrides = (scene_config, body, shape)
        self._scenes = InstanceCache(self._build_scene, MODEL_CACHE_SIZE)
        self._instance = self._scenes.get

    # ------------------------------------------------------------------ scene
    def _material(self, friction: float) -> Any:
        # Static = dynamic friction (MuJoCo has one coefficient); restitution 0.
        return self._sapien.physx.PhysxMaterial(friction, friction, 0.0)

    def _plate(self, scene: Any, x_hole: float, c: float) -> None:
        """Static plate: the tap's stretch frictionless, the peg's with friction 0.3."""
        sapien, physx = self._sapien, self._sapien.physx
        component = physx.PhysxRigidStaticComponent()
        for stretch, friction in ((-1.0, 0.0), (1.0, PEG_FRICTION)):
            material = self._material(friction)
            boxes = plate_boxes(x_hole, c)
            hy = boxes[0]["half"][1]
            y = stretch * hy / 2  # each stretch is half the plate's length
            if self.plate == "boxes":
                for b in boxes:
                    shape = physx.PhysxCollisionShapeBox(np.array([b["half"][0], hy / 2, b["half"][2]]), material)
                    shape.set_local_pose(sapien.Pose([b["pos"][0], y, b["pos"][2]], b["quat"]))
                    component.attach(shape)
            else:
                floor = next(b for b in boxes if b["name"] == "floor")
                shape = physx.PhysxCollisionShapeBox(np.array([floor["half"][0], hy / 2, floor["half"][2]]), material)
                shape.set_local_pose(sapien.Pose([floor["pos"][0], y, floor["pos"][2]]))
                component.attach(shape)
                for centre, verts in plate_prisms(x_hole, c, hy / 2):
                    shape = physx.PhysxCollisionShapeConvexMesh(verts.astype(np.float32), np.ones(3, np.float32), material)
                    shape.set_local_pose(sapien.Pose([centre[0], y, centre[2]]))
                    component.attach(shape)
        self._se.mm_shapes(component, self._overrides[2])
        entity = sapien.Entity()
        entity.set_name("plate")
        entity.add_component(component)
        scene.add_entity(entity)

    def _chain(self, scene: Any, name: str, base: list[float], mass: float, inertia: list[float],
               friction: float, add_shape) -> Any:
        """A fixed-root articulation: prismatic x carriage, then a prismatic z link with the shape."""
        sapien = self._sapien
        ab = scene.create_articulation_builder()
        ab.set_initial_pose(sapien.Pose(base))
        root = ab.create_link_builder()
        root.set_mass_and_inertia(1.0, sapien.Pose(), [1e-6] * 3)  # fixed: never moves
        carriage = ab.create_link_builder(root)
        carriage.set_joint_properties("prismatic", [[-np.inf, np.inf]], sapien.Pose(), sapien.Pose())
        carriage.set_mass_and_inertia(CARRIAGE_MASS_KG, sapien.Pose(), [CARRIAGE_INERTIA] * 3)
        tip = ab.create_link_builder(carriage)
        frame = sapien.Pose([0, 0, 0], list(_X_TO_Z))
        tip.set_joint_properties("prismatic", [[-np.inf, np.inf]], frame, frame)
        tip.set_mass_and_inertia(mass, sapien.Pose(), inertia)
        add_shape(tip, self._material(friction))
        art = ab.build(fix_root_link=True)
        art.set_name(name)
        self._se.mm_articulation(art, self._overrides[1], self._overrides[2])
        return art

    def _build_scene(self, x_hole: float, c: float) -> dict[str, Any]:
        """The instance's PhysX scene with plate, tap and peg (kept by the LRU ``self._instance``)."""
        sapien = self._sapien
        scene = self._se.new_scene(TIMESTEP_S, self._overrides[0])
        self._plate(scene, x_hole, c)
        r = TIP_RADIUS_MM * MM
        tap_base = [0.0, TAP_Y_MM * MM, r + START_CLEARANCE_MM * MM]
        tap = self._chain(scene, "tap", tap_base, TAP_MASS_KG, [0.4 * TAP_MASS_KG * r * r] * 3, 0.0,
                          lambda lb, m: lb.add_sphere_collision(sapien.Pose(), r, material=m))
        pw, pl, ph = PEG_HALF_WIDTH_MM * MM, PEG_HALF_LENGTH_MM * MM, PEG_HALF_HEIGHT_MM * MM
        peg_base = [0.0, PEG_Y_MM * MM, ph + PEG_START_CLEARANCE_MM * MM]
        peg_inertia = [PEG_MASS_KG / 3 * (pl * pl + ph * ph), PEG_MASS_KG / 3 * (pw * pw + ph * ph),
                       PEG_MASS_KG / 3 * (pw * pw + pl * pl)]
        peg = self._chain(scene, "peg", peg_base, PEG_MASS_KG, peg_inertia, PEG_FRICTION,
                          lambda lb, m: lb.add_box_collision(sapien.Pose(), (pw, pl, ph), material=m))
        return {"scene": scene, "tap": tap, "peg": peg, "tap_z0": tap_base[2], "peg_z0": peg_base[2]}

    @staticmethod
    def _reset(entry: dict[str, Any]) -> None:
        """Both probes at their start pose, at rest, with drives that hold them there."""
        for art in (entry["tap"], entry["peg"]):
            art.set_qpos(np.zeros(2, dtype=np.float32))
            art.set_qvel(np.zeros(2, dtype=np.float32))
            for joint in art.active_joints:
                joint.set_drive_properties(0.0, 0.0, 0.0, "force")  # off: idle body never moves
                joint.set_drive_target(0.0)
                joint.set_drive_velocity_target(0.0)

    def _descend(self, entry: dict[str, Any], art: Any, schedule=None) -> np.ndarray:
        """Step until the driven link is in contact and both joint speeds stay settled.

        Same chunked rule as MuJoCo's: chunks of ``CHUNK_STEPS``, stop after
        ``SETTLE_CHUNKS`` quiet chunks in contact, cap ``MAX_TIME_S``.

        Returns:
            Final joint positions (x, z) in metres.
        """
        scene, link = entry["scene"], art.links[-1]
        quiet = 0
        max_chunks = int(round(MAX_TIME_S / (TIMESTEP_S * CHUNK_STEPS)))
        for _ in range(max_chunks):
            for _ in range(CHUNK_STEPS):
                if schedule is not None:
                    schedule(art)
                scene.step()
            v = art.get_qvel()
            touching = any(link in con.bodies and len(con.points) > 0 for con in scene.get_contacts())
            if touching and abs(float(v[0])) < SETTLE_SPEED and abs(float(v[1])) < SETTLE_SPEED:
                quiet += 1
                if quiet >= SETTLE_CHUNKS:
                    break
            else:
                quiet = 0
        return np.asarray(art.get_qpos(), dtype=np.float64)

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
        entry = self._instance(x_hole, c)
        self._reset(entry)
        tap = entry["tap"]
        jx, jz = tap.active_joints
        tap.set_qpos(np.array([u * MM, 0.0], dtype=np.float32))
        jx.set_drive_properties(TAP_LATERAL_STIFFNESS, TAP_LATERAL_DAMPING, 3.4e38, "force")
        jx.set_drive_target(u * MM)
        # Constant 0.5 N push + 2.5 N s/m damper == damper toward a -0.2 m/s velocity target.
        jz.set_drive_properties(0.0, TAP_FORCE_N / TAP_DESCENT_SPEED, 3.4e38, "force")
        jz.set_drive_velocity_target(-TAP_DESCENT_SPEED)
        q = self._descend(entry, tap)
        return float((entry["tap_z0"] + q[1] - TIP_RADIUS_MM * MM) / MM)

    def peg_depth(self, x_hole: float, c: float, a: float) -> float:
        """How far (mm, positive down) below the plate top the peg's bottom reached.

        Args:
            x_hole: Slot centre (mm).
            c: Clearance scale.
            a: Lateral aim (mm), already including any frame offset.

        Returns:
            About 15.0 when the peg reaches the pocket floor, about 0.0 when it rests on top.
        """
        entry = self._instance(x_hole, c)
        self._reset(entry)
        peg = entry["peg"]
        jx, jz = peg.active_joints
        peg.set_qpos(np.array([a * MM, 0.0], dtype=np.float32))
        jx.set_drive_properties(PEG_LATERAL_STIFFNESS, PEG_LATERAL_DAMPING, 3.4e38, "force")
        jx.set_drive_target(a * MM)
        jz.set_drive_properties(0.0, PEG_SERVO_GAIN, PEG_FORCE_N, "force")
        fast_below = -(PEG_START_CLEARANCE_MM + PEG_FAST_BELOW_MM) * MM

        def schedule(art: Any) -> None:
            # MuJoCo's guarded approach: slow until the bottom is past the chamfer.
            qz = float(art.get_qpos()[1])
            jz.set_drive_velocity_target(-(PEG_INSERT_SPEED if qz < fast_below else PEG_APPROACH_SPEED))

        q = self._descend(entry, peg, schedule)
        return float(-(entry["peg_z0"] + q[1] - PEG_HALF_HEIGHT_MM * MM) / MM)

    def close(self) -> None:
        """Drop every cached PhysX scene (idempotent)."""
        self._scenes.clear()
