"""Scene renders of the task families, on the CPU: MuJoCo through EGL or OSMesa (Mesa's
software rasterizer), PyBullet's TinyRenderer, and the SAPIEN shuffleboard scene drawn
from its geometry with matplotlib (SAPIEN 3 finds no render device without a GPU), labelled so.

Each render is of the scene the simulator builds (the same MJCF, the same plate boxes),
coloured for the picture only. A render is an RGB array plus a segmentation mask (which
object each pixel shows), so the background turns white and a test can check that a
known object fills a region of the image, not only that a file exists.

MuJoCo picks its GL back-end when it is first imported (``MUJOCO_GL``); a process that
already imported it for physics cannot switch, so :func:`render_scenes` runs the renders
in a child process with ``MUJOCO_GL`` set (``egl``, then ``osmesa``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from probecommit.store.safefile import write_text

#: Colours of the picture (RGBA 0..1); the tests look for these hues.
PLATE = (0.30, 0.45, 0.75, 1.0)  # steel blue
TIP = (0.85, 0.15, 0.15, 1.0)  # red
PEG = (0.95, 0.60, 0.10, 1.0)  # orange
FLOOR = (0.80, 0.80, 0.78, 1.0)
OBJECT = (0.20, 0.65, 0.30, 1.0)  # green: the manipulated object of the other families
#: Render size (pixels); the figure places it at a fraction of a 3.5 in column.
SIZE = (360, 480)


@dataclass
class Render:
    """One scene image: RGB (H, W, 3, uint8), the pixel fraction each named object covers,
    and what drew it (engine, renderer)."""

    family: str
    engine: str
    renderer: str
    rgb: np.ndarray
    fractions: dict[str, float] = field(default_factory=dict)

    @property
    def label(self) -> str:
        return f"{self.family} ({self.engine})"


# ----------------------------------------------------------------------------- MuJoCo


def _mujoco_render(xml: str, colors: dict[str, tuple], camera: dict[str, Any], qpos: dict[str, float] | None = None,
                   named: tuple[str, ...] = ()) -> tuple[np.ndarray, dict[str, float]]:
    """Render an MJCF string from a free camera; geoms coloured by geom or body name; white background.

    Returns:
        RGB image and the pixel fraction of each geom or body named in ``named`` (prefix match).
    """
    import mujoco

    model = mujoco.MjModel.from_xml_string(xml)
    names = []
    for g in range(model.ngeom):
        gname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
        bname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.geom_bodyid[g]) or ""
        names.append(gname or bname)
        for key, rgba in colors.items():
            if gname.startswith(key) or (not gname and bname.startswith(key)) or (key == bname):
                model.geom_rgba[g] = rgba
                break
    model.vis.headlight.ambient[:] = (0.45, 0.45, 0.45)
    model.vis.headlight.diffuse[:] = (0.6, 0.6, 0.6)
    data = mujoco.MjData(model)
    for joint, value in (qpos or {}).items():
        data.qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)]] = value
    mujoco.mj_forward(model, data)
    cam = mujoco.MjvCamera()
    cam.lookat[:] = camera["lookat"]
    cam.distance, cam.azimuth, cam.elevation = camera["distance"], camera["azimuth"], camera["elevation"]
    with mujoco.Renderer(model, *SIZE) as renderer:
        renderer.update_scene(data, cam)
        rgb = renderer.render().copy()
        renderer.enable_segmentation_rendering()
        renderer.update_scene(data, cam)
        seg = renderer.render()[..., 0].copy()
    rgb[seg < 0] = 255  # background white
    fractions = {key: float(np.isin(seg, [g for g, n in enumerate(names) if n.startswith(key)]).mean()) for key in named}
    return rgb, fractions


def insertion_mujoco(taps: list[tuple[float, bool]] | None = None, peg_at: float | None = None,
                     x_hole: float = 2.0, c: float = 1.0) -> Render:
    """The insertion plate with its slot; ``taps`` as ghost tips ``(u mm, read pocket)``; the peg at ``peg_at`` (mm)."""
    from probecommit.tasks.insertion import sim_mujoco as S
    from probecommit.tasks.insertion.model import POCKET_DEPTH_MM, TIP_RADIUS_MM

    xml = S.scene_xml(x_hole, c)
    ghosts = []
    for j, (u, pocket) in enumerate(taps or []):
        z = (-POCKET_DEPTH_MM + TIP_RADIUS_MM) if pocket else TIP_RADIUS_MM
        ghosts.append(f'<geom name="ghost{j}" type="sphere" size="{TIP_RADIUS_MM * S.MM}" contype="0" conaffinity="0" '
                      f'pos="{u * S.MM} {S.TAP_Y_MM * S.MM} {z * S.MM}"/>')
    xml = xml.replace("  </worldbody>", "    " + "\n    ".join(ghosts) + "\n  </worldbody>", 1)
    qpos = {"tap_z": 400 * S.MM}  # the live tip lifted out of view: the ghosts show where it touched
    if peg_at is None:
        qpos.update({"peg_z": 60 * S.MM})
    else:
        qpos.update({"peg_x": peg_at * S.MM, "peg_z": -8 * S.MM})  # the peg part-way into the slot at the aim
    camera = {"lookat": (x_hole * S.MM, -0.01, -5 * S.MM), "distance": 0.1, "azimuth": 100, "elevation": -42}
    colors = {"ghost": TIP, "tip": TIP, "peg": PEG, "floor": PLATE, "left": PLATE, "right": PLATE}
    rgb, fr = _mujoco_render(xml, colors, camera, qpos, named=("left", "right", "floor", "ghost", "peg"))
    fractions = {"plate": fr["left"] + fr["right"] + fr["floor"], "tip": fr["ghost"], "peg": fr["peg"]}
    return Render("insertion", "MuJoCo", "MuJoCo OpenGL (software)", rgb, fractions)


def _floor_plane(xml: str) -> str:
    """A visible floor for scenes whose ground has no geom (hinge, grasp); visual only."""
    floor = '<geom name="floor" type="plane" size="2 2 0.1" contype="0" conaffinity="0"/>'
    return xml.replace("<worldbody>", "<worldbody>\n    " + floor, 1)


def other_mujoco(family: str) -> Render:
    """Push2d, darts, hinge and grasp as MuJoCo builds them (a mid-prior truth; geometry does not depend on it)."""
    if family == "push2d":
        from probecommit.tasks.push2d.sim_mujoco import scene_xml

        xml, cam = scene_xml(0.4, 1.0, 0.5), {"lookat": (0.0, 0.0, 0.05), "distance": 0.7, "azimuth": 135, "elevation": -30}
        key = "box"
    elif family == "darts":
        from probecommit.tasks.darts.model import RELEASE_HEIGHT
        from probecommit.tasks.darts.sim_mujoco import scene_xml

        xml = scene_xml(0.05, 0.1, 9.81)
        # the sphere drawn larger than it is (1 cm) so it shows at the scale of its 1 m fall; a target mark on the floor
        xml = xml.replace('name="dart" type="sphere" size="0.01"', 'name="dart" type="sphere" size="0.06"')
        xml = xml.replace("  </worldbody>", '    <geom name="target" type="cylinder" size="0.15 0.002" pos="1.5 0 0.002" '
                          'contype="0" conaffinity="0" rgba="0.85 0.15 0.15 1"/>\n  </worldbody>', 1)
        cam = {"lookat": (0.75, 0.0, RELEASE_HEIGHT / 2), "distance": 3.2, "azimuth": 90, "elevation": -12}
        key = "dart"
    elif family == "hinge":
        from probecommit.tasks.hinge.sim_mujoco import scene_xml

        xml = _floor_plane(scene_xml(0.5, 0.5, 5.0))
        cam = {"lookat": (0.25, 0.0, 0.4), "distance": 2.0, "azimuth": 120, "elevation": -20}
        key = "door"
    elif family == "grasp":
        from probecommit.tasks.grasp.sim_mujoco import HAND_Z, scene_xml

        xml = scene_xml(0.5, 0.2)
        cam = {"lookat": (0.0, 0.0, HAND_Z), "distance": 0.3, "azimuth": 120, "elevation": -20}
        key = "object"
    else:
        raise ValueError(f"no MuJoCo scene render for {family!r}")
    colors = {"floor": FLOOR, key: OBJECT, "left": PLATE, "right": PLATE, "hand": PLATE}
    qpos = {"left_x": 0.004, "right_x": -0.004} if family == "grasp" else None
    rgb, fr = _mujoco_render(xml, colors, cam, qpos, named=(key,))
    return Render(family, "MuJoCo", "MuJoCo OpenGL (software)", rgb, {"object": fr[key]})


# ----------------------------------------------------------------------------- PyBullet


def _pybullet_camera(p, cid: int, target, distance: float, yaw: float, pitch: float):
    view = p.computeViewMatrixFromYawPitchRoll(target, distance, yaw, pitch, 0, 2, physicsClientId=cid)
    proj = p.computeProjectionMatrixFOV(45, SIZE[1] / SIZE[0], 0.01, 50, physicsClientId=cid)
    _, _, rgba, _, seg = p.getCameraImage(SIZE[1], SIZE[0], view, proj, renderer=p.ER_TINY_RENDERER,
                                          lightDirection=[-1, -2, 3], physicsClientId=cid)
    rgb = np.asarray(rgba, np.uint8).reshape(SIZE[0], SIZE[1], 4)[..., :3].copy()
    seg = np.asarray(seg).reshape(SIZE[0], SIZE[1])
    rgb[seg < 0] = 255
    return rgb, seg


def insertion_pybullet(x_hole: float = 2.0, c: float = 1.0) -> Render:
    """The insertion plate as PyBullet builds it (the MuJoCo scene's boxes), TinyRenderer."""
    from probecommit.engines.pybullet import disconnect, import_pybullet
    from probecommit.tasks.insertion.sim_pybullet import plate_boxes

    p = import_pybullet()
    cid = p.connect(p.DIRECT)
    try:
        ids = []
        for box in plate_boxes(x_hole, c):
            w, x, y, z = box["quat"]
            vis = p.createVisualShape(p.GEOM_BOX, halfExtents=box["half"], rgbaColor=PLATE, physicsClientId=cid)
            ids.append(p.createMultiBody(0.0, -1, vis, box["pos"], [x, y, z, w], physicsClientId=cid))
        tip = p.createVisualShape(p.GEOM_SPHERE, radius=0.0012, rgbaColor=TIP, physicsClientId=cid)
        tip_id = p.createMultiBody(0.0, -1, tip, [0.0, -0.02, 0.0012], physicsClientId=cid)
        rgb, seg = _pybullet_camera(p, cid, [x_hole * 1e-3, -0.01, -0.005], 0.1, 10, -42)
    finally:
        disconnect(cid)
    fractions = {"plate": float(np.isin(seg, ids).mean()), "tip": float((seg == tip_id).mean())}
    return Render("insertion", "PyBullet", "PyBullet TinyRenderer", rgb, fractions)


def push2d_pybullet() -> Render:
    """The 2-D push box on its plane as PyBullet builds it, TinyRenderer."""
    from probecommit.engines.pybullet import disconnect, import_pybullet
    from probecommit.tasks.push2d.sim_pybullet import BOX_HALF_M

    p = import_pybullet()
    cid = p.connect(p.DIRECT)
    try:
        plane = p.createVisualShape(p.GEOM_BOX, halfExtents=[1, 1, 0.001], rgbaColor=FLOOR, physicsClientId=cid)
        p.createMultiBody(0.0, -1, plane, [0, 0, -0.001], physicsClientId=cid)
        box = p.createVisualShape(p.GEOM_BOX, halfExtents=[BOX_HALF_M] * 3, rgbaColor=OBJECT, physicsClientId=cid)
        box_id = p.createMultiBody(0.0, -1, box, [0, 0, BOX_HALF_M], physicsClientId=cid)
        rgb, seg = _pybullet_camera(p, cid, [0, 0, 0.05], 0.7, 45, -30)
    finally:
        disconnect(cid)
    return Render("push2d", "PyBullet", "PyBullet TinyRenderer", rgb, {"object": float((seg == box_id).mean())})


# ----------------------------------------------------------------------------- SAPIEN (drawn, not rendered)


def shuffleboard_drawn() -> Render:
    """The SAPIEN shuffleboard scene (board and puck boxes, the same dimensions) drawn in an
    oblique projection with matplotlib: SAPIEN 3 needs a render device this machine lacks."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from probecommit.tasks.shuffleboard.sim_sapien import BOARD_HALF, PUCK_HALF

    def box(centre, half):
        cx, cy, cz = centre
        hx, hy, hz = half
        v = np.array([[cx + sx * hx, cy + sy * hy, cz + sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        faces = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]]
        return [v[f] for f in faces]

    fig = plt.figure(figsize=(SIZE[1] / 100, SIZE[0] / 100), dpi=100)
    ax = fig.add_subplot(projection="3d", computed_zorder=False)  # the puck on top of the board, drawn after it
    # The first 3 m of the board (it runs 2 x BOARD_HALF[0] along +x), where the puck starts; the puck enlarged 10x to be seen.
    near_half = (1.5, BOARD_HALF[1], BOARD_HALF[2])
    ax.add_collection3d(Poly3DCollection(box((1.2, 0, -BOARD_HALF[2]), near_half), facecolor=PLATE[:3], edgecolor="0.2", lw=0.3))
    scale = 10
    puck_half = tuple(h * scale for h in PUCK_HALF)
    ax.add_collection3d(Poly3DCollection(box((0, 0, puck_half[2]), puck_half), facecolor=OBJECT[:3], edgecolor="0.1", lw=0.3))
    ax.set_xlim(-0.5, 2.7)
    ax.set_ylim(-1.6, 1.6)
    ax.set_zlim(-0.6, 1.0)
    ax.view_init(elev=30, azim=-120)
    ax.set_axis_off()
    fig.subplots_adjust(0, 0, 1, 1)
    fig.canvas.draw()
    rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    plt.close(fig)
    green = (rgb[..., 1].astype(int) - rgb[..., 0] > 40) & (rgb[..., 1].astype(int) - rgb[..., 2] > 40)
    blue = (rgb[..., 2].astype(int) - rgb[..., 0] > 40)
    return Render("shuffleboard", "SAPIEN geometry", "matplotlib (no SAPIEN render device)", rgb,
                  {"object": float(green.mean()), "plate": float(blue.mean())})


# ----------------------------------------------------------------------------- all of them

#: (file stem, family, engine, function) of every scene render, Fig. 3's order.
SCENES = (
    ("scene_insertion_mujoco", "insertion", "MuJoCo", lambda: insertion_mujoco()),
    ("scene_insertion_pybullet", "insertion", "PyBullet", insertion_pybullet),
    ("scene_push2d_mujoco", "push2d", "MuJoCo", lambda: other_mujoco("push2d")),
    ("scene_push2d_pybullet", "push2d", "PyBullet", push2d_pybullet),
    ("scene_darts_mujoco", "darts", "MuJoCo", lambda: other_mujoco("darts")),
    ("scene_hinge_mujoco", "hinge", "MuJoCo", lambda: other_mujoco("hinge")),
    ("scene_grasp_mujoco", "grasp", "MuJoCo", lambda: other_mujoco("grasp")),
    ("scene_shuffleboard_drawn", "shuffleboard", "SAPIEN", shuffleboard_drawn),
)


def _save(render: Render, out: Path, stem: str) -> dict[str, Any]:
    from PIL import Image

    Image.fromarray(render.rgb).save(out / f"{stem}.png")
    return {"file": f"{stem}.png", "family": render.family, "engine": render.engine, "renderer": render.renderer,
            "fractions": render.fractions}


def render_all(out: str | Path, fig1: dict[str, Any] | None = None) -> dict[str, Any]:
    """Render every scene that this machine can into ``out`` (PNG each) and write ``scenes.json``:
    per scene its renderer and object pixel fractions, or why it was skipped."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    done: dict[str, Any] = {"renders": [], "skipped": [], "gl": os.environ.get("MUJOCO_GL", "")}
    jobs = list(SCENES)
    if fig1:  # Fig. 1a (the taps of one episode) and 1c (the peg at that episode's aim)
        taps = [(float(u), bool(p)) for u, p in fig1["taps"]]
        jobs += [("scene_fig1a_taps", "insertion", "MuJoCo",
                  lambda: insertion_mujoco(taps=taps, x_hole=fig1["x_hole"], c=fig1["c"])),
                 ("scene_fig1c_insertion", "insertion", "MuJoCo",
                  lambda: insertion_mujoco(peg_at=fig1["aim"], x_hole=fig1["x_hole"], c=fig1["c"]))]
    for stem, family, engine, make in jobs:
        try:
            done["renders"].append(_save(make(), out, stem))
        except Exception as exc:  # an engine or GL library missing: say which, go on with the others
            done["skipped"].append({"file": f"{stem}.png", "family": family, "engine": engine,
                                    "reason": f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"[:300]})
    write_text(out / "scenes.json", json.dumps(done, indent=1))
    return done


def render_scenes(out: str | Path, fig1: dict[str, Any] | None = None, timeout: float = 600) -> dict[str, Any]:
    """:func:`render_all` in a child process with a software GL back-end: ``MUJOCO_GL`` as set
    by the user, else EGL, else OSMesa (the first whose MuJoCo renders succeed)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    choices = [os.environ["MUJOCO_GL"]] if os.environ.get("MUJOCO_GL") else ["egl", "osmesa"]
    result: dict[str, Any] = {}
    for gl in choices:
        env = {**os.environ, "MUJOCO_GL": gl, "PYOPENGL_PLATFORM": gl}
        spec = json.dumps(fig1 or {})
        proc = subprocess.run([sys.executable, "-m", "probecommit.report.scenes", str(out), spec], env=env,
                              capture_output=True, text=True, timeout=timeout)
        if (out / "scenes.json").is_file():
            result = json.loads((out / "scenes.json").read_text())
        else:
            result = {"renders": [], "skipped": [{"file": "*", "reason": proc.stderr[-300:]}], "gl": gl}
        if any(r["engine"] == "MuJoCo" for r in result["renders"]):
            break
    return result


if __name__ == "__main__":  # python -m probecommit.report.scenes OUT [FIG1-JSON]
    render_all(sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 and sys.argv[2] != "{}" else None)
