"""SAPIEN 3 (PhysX) plumbing shared by every task family: a quiet import, headless
millimetre-safe scenes, and per-shape / per-articulation settings.

SAPIEN's import warns (Python ``warnings`` and C-level prints) that it falls back to
its own libvulkan; :func:`import_sapien` keeps that off the user's terminal. Scenes are
physics-only, ``sapien.Scene([PhysxCpuSystem()])`` with collision shapes alone (no
visual shape, no ``add_ground``: both want a render device). SAPIEN's defaults are
metre-scale; :data:`MM_SCENE`, :data:`MM_SHAPE` and :data:`MM_BODY` are the settings for
millimetre contact, each measured in ``docs/engines.md``.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

from probecommit.engines import require, silenced_fds

#: PhysxSceneConfig fields, read by PhysxCpuSystem() at construction. Defaults in brackets.
MM_SCENE: dict[str, Any] = {
    "gravity": (0.0, 0.0, 0.0),  # [(0, 0, -9.81)] the task's drives set every force
    "enable_enhanced_determinism": True,  # [False] results independent of pair/insertion history
    "enable_ccd": False,  # [False] kept: at most 0.04 mm of travel per 0.2 ms step, << 1.2 mm tip
    "enable_pcm": True,  # [True] persistent contact manifolds
    "enable_tgs": True,  # [True] temporal Gauss-Seidel
    "bounce_threshold": 2.0,  # [2 m/s] kept; restitution is 0 on every material
}

#: Per collision shape (metres). Defaults in brackets.
MM_SHAPE: dict[str, float] = {
    # [0.01 m = 8x the 1.2 mm tip] contacts are generated once shapes are this close: 0.1 mm,
    # still > 2x the largest travel per step (0.2 m/s x 0.2 ms = 0.04 mm).
    "contact_offset": 1e-4,
    "rest_offset": 0.0,  # [0] surfaces rest touching, not apart
}

#: Per articulation / dynamic body. Defaults in brackets.
MM_BODY: dict[str, Any] = {
    # [0.005 (m/s)^2 mass-normalised energy, i.e. ~0.1 m/s] a 10 mm/s guarded approach would
    # count as asleep; never sleep.
    "sleep_threshold": 0.0,
    "solver_position_iterations": 32,  # [10]
    "solver_velocity_iterations": 4,  # [1]
    "linear_damping": 0.0,  # [0.05] the drives set all damping explicitly
    "angular_damping": 0.0,  # [0.05]
    "joint_friction": 0.0,  # [0.05] articulation joint friction
}


def import_sapien() -> ModuleType:
    """Import sapien without its libvulkan warning reaching the terminal.

    Returns:
        The ``sapien`` module.

    Raises:
        EngineUnavailableError: sapien is not installed (names the extra).
    """
    with silenced_fds():
        return require("sapien")


def new_scene(timestep: float, scene_config: dict[str, Any] | None = None) -> Any:
    """A headless CPU PhysX scene with millimetre settings and the given step.

    The scene config is process-global in SAPIEN and read when the system is built, so
    it is set for this construction only and the previous one restored afterwards.

    Args:
        timestep: Fixed step (s).
        scene_config: Overrides of :data:`MM_SCENE` fields.

    Returns:
        The ``sapien.Scene``.
    """
    sapien = import_sapien()
    physx = sapien.physx
    previous = physx.get_scene_config()
    config = physx.get_scene_config()
    for key, value in {**MM_SCENE, **(scene_config or {})}.items():
        setattr(config, key, list(value) if key == "gravity" else value)
    physx.set_scene_config(config)
    try:
        with silenced_fds():
            scene = sapien.Scene([physx.PhysxCpuSystem()])
    finally:
        physx.set_scene_config(previous)
    scene.set_timestep(timestep)
    return scene


def mm_shapes(component: Any, shape: dict[str, float] | None = None) -> None:
    """Apply :data:`MM_SHAPE` to every collision shape of a physx component.

    Args:
        component: A rigid body or articulation link component.
        shape: Overrides of :data:`MM_SHAPE`.
    """
    settings = {**MM_SHAPE, **(shape or {})}
    for s in component.collision_shapes:
        # Contact offset must stay above the rest offset; set it first when it grows.
        s.set_contact_offset(settings["contact_offset"])
        s.set_rest_offset(settings["rest_offset"])


def mm_articulation(articulation: Any, body: dict[str, Any] | None = None, shape: dict[str, float] | None = None) -> None:
    """Apply :data:`MM_BODY` and :data:`MM_SHAPE` to an articulation, its links and joints.

    Args:
        articulation: A ``PhysxArticulation``.
        body: Overrides of :data:`MM_BODY`.
        shape: Overrides of :data:`MM_SHAPE`.
    """
    settings = {**MM_BODY, **(body or {})}
    articulation.set_sleep_threshold(settings["sleep_threshold"])
    articulation.set_solver_position_iterations(settings["solver_position_iterations"])
    articulation.set_solver_velocity_iterations(settings["solver_velocity_iterations"])
    for link in articulation.links:
        link.set_linear_damping(settings["linear_damping"])
        link.set_angular_damping(settings["angular_damping"])
        link.set_disable_gravity(True)
        mm_shapes(link, shape)
    for joint in articulation.active_joints:
        joint.set_friction(settings["joint_friction"])
