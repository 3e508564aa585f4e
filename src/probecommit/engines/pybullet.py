"""PyBullet plumbing shared by every task family: a quiet import and millimetre-safe clients.

PyBullet prints a build banner ("pybullet build time: ...") from C code on import;
:func:`import_pybullet` keeps it off the user's terminal. :func:`new_client` opens one
``p.DIRECT`` client (no GUI, no shared memory) and applies :data:`MM_PHYSICS`, the
engine parameters chosen for millimetre contact; see ``docs/engines.md`` for each
setting and the measurement behind it.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

from probecommit.engines import require, silenced_fds

#: Engine parameters for millimetre scenes (``setPhysicsEngineParameter`` keywords).
#: Defaults in brackets; docs/engines.md has the measurements.
MM_PHYSICS: dict[str, Any] = {
    "contactSlop": 1e-6,  # [1e-5 m] resting penetration left uncorrected: the tap sinks by exactly this
    "contactBreakingThreshold": 1e-4,  # [0.02 m] keep contact points only up to 0.1 mm apart,
    #   not across the 9-10 mm slot; still > 2x the largest travel per step (0.04 mm)
    "deterministicOverlappingPairs": 1,  # sort broadphase pairs: results independent of history
    "restitutionVelocityThreshold": 0.0,  # restitution is 0 on every body anyway
    "numSolverIterations": 50,  # [50] kept: 200 changes no reading (docs/engines.md)
}

#: Per-body contact settings (``changeDynamics`` keywords) applied to every body and link.
MM_DYNAMICS: dict[str, Any] = {
    "contactProcessingThreshold": 1e-4,  # [BT_LARGE_FLOAT / 0.02 m] as contactBreakingThreshold
    "restitution": 0.0,
    "spinningFriction": 0.0,
    "rollingFriction": 0.0,
    "linearDamping": 0.0,  # [0.04] the drives set all damping explicitly
    "angularDamping": 0.0,
}

#: Collision margin (m) set on every collision shape. PyBullet's box-box and sphere-box
#: algorithms are exact; the margin only rounds GJK edges, so keep it far below the 0.9 mm chamfer.
COLLISION_MARGIN_M = 1e-5


def import_pybullet() -> ModuleType:
    """Import pybullet without its build banner reaching the terminal.

    Returns:
        The ``pybullet`` module.

    Raises:
        EngineUnavailableError: pybullet is not installed (names the extra).
    """
    with silenced_fds():
        return require("pybullet")


def new_client(timestep: float, physics: dict[str, Any] | None = None) -> int:
    """Open a ``p.DIRECT`` client with gravity off and millimetre contact settings.

    Args:
        timestep: Fixed step (s).
        physics: Overrides of :data:`MM_PHYSICS` (for measurements, e.g. PyBullet defaults).

    Returns:
        The physics client id; the caller owns it and must ``disconnect`` it.
    """
    p = import_pybullet()
    with silenced_fds():
        cid = p.connect(p.DIRECT)
    p.resetSimulation(physicsClientId=cid)
    p.setGravity(0.0, 0.0, 0.0, physicsClientId=cid)
    params = dict(MM_PHYSICS if physics is None else physics)
    p.setPhysicsEngineParameter(fixedTimeStep=timestep, physicsClientId=cid, **params)
    return cid


def mm_dynamics(body: int, link: int, cid: int, **extra: Any) -> None:
    """Apply :data:`MM_DYNAMICS` and the collision margin to one body link.

    Args:
        body: Body unique id.
        link: Link index (-1 for the base).
        cid: Physics client id.
        **extra: Further ``changeDynamics`` keywords (friction, ...).
    """
    p = import_pybullet()
    p.changeDynamics(body, link, physicsClientId=cid, **{**MM_DYNAMICS, **extra})
    # Separate call: in pybullet 3.2.7 a changeDynamics that also sets collisionMargin on a
    # link silently drops the other keywords (friction, inertia) for that link.
    p.changeDynamics(body, link, collisionMargin=COLLISION_MARGIN_M, physicsClientId=cid)


def disconnect(cid: int | None) -> None:
    """Disconnect a client, ignoring one already gone (safe in ``__del__``)."""
    if cid is None:
        return
    try:
        p = import_pybullet()
        if p.isConnected(physicsClientId=cid):
            p.disconnect(physicsClientId=cid)
    except Exception:  # noqa: BLE001 - interpreter shutdown: modules may be half torn down
        pass
