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
    "deterministicOverlappingPairs": 1,  # sort broadphase pairs: results independent of history
    "restitutionVelocityThreshold": 0.0,  # restitution is 0 on every body anyway
    "numSolverIterations": 50,  # [50] kept: 200 moves the tap boundary by 0.0016 mm, nothing else
    # contactBreakingThreshold is deliberately left at its default (0.02 m): at 1e-4 m the peg
    # snags on the chamfer (capture 0.45-0.93 w on some truths, against 1.000 w at the
    # default), and Bullet keeps it in a process-global variable, so setting it on one client
    # silently changes every other client in the process (docs/engines.md).
}

#: Per-body contact settings (``changeDynamics`` keywords) applied to every body and link.
MM_DYNAMICS: dict[str, Any] = {
    "restitution": 0.0,
    "spinningFriction": 0.0,
    "rollingFriction": 0.0,
    "linearDamping": 0.0,  # [0.04] the drives set all damping explicitly
    "angularDamping": 0.0,
}

#: Collision margin (m) set on every body (the plate's compound passes it to its boxes).
#: Essential: with PyBullet's default margin the tap boundary scatters to hg + 1.60 mm
#: (SD 0.32 over 8 truths) instead of hg + 0.913 (SD 0.0005); see docs/engines.md.
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


def mm_dynamics(body: int, link: int, cid: int, margin: float | None = COLLISION_MARGIN_M, **extra: Any) -> None:
    """Apply :data:`MM_DYNAMICS` and the collision margin to one body link.

    Args:
        body: Body unique id.
        link: Link index (-1 for the base).
        cid: Physics client id.
        margin: Collision margin (m); None leaves PyBullet's default (for measurements).
        **extra: Further ``changeDynamics`` keywords (friction, ...).
    """
    p = import_pybullet()
    p.changeDynamics(body, link, physicsClientId=cid, **{**MM_DYNAMICS, **extra})
    if margin is not None:
        # Separate call: in pybullet 3.2.7 a changeDynamics that also sets collisionMargin on a
        # link silently drops the other keywords (friction, inertia) for that link.
        p.changeDynamics(body, link, collisionMargin=margin, physicsClientId=cid)


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
