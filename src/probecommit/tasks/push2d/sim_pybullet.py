"""2-D push ground truth in PyBullet: the MuJoCo scene rebuilt, for the transfer row of Table V.

The same 10 cm cube of mass ``m`` on a plane (``BOX_HALF_M``, ``TIMESTEP_S``, the settle,
stop and chunk rules are imported from :mod:`.sim_mujoco`). The box rides a fixed-base
chain of three prismatic joints (x, y, z; two massless-carriage links), so, as in MuJoCo,
it slides without turning. Coulomb friction ``mu``: PyBullet multiplies the two bodies'
friction coefficients, so the plane's is 1 and the box's is ``mu``. Linear damping
``k_d``: an explicit joint force ``-k_d v`` on x and y every step (PyBullet's own
``linearDamping`` is a per-step velocity scale, not ``k_d``). Gravity 9.81 m/s^2 down.
The analytic model is the MuJoCo-fitted one, unchanged (the paper's transfer case).

A query resets the chain (the box at its start pose), lets it settle for ``SETTLE_S``,
sets the horizontal velocity to ``J / m`` and steps in chunks until the horizontal speed
stays below ``STOP_SPEED``: a deterministic function of ``(theta, impulse)``, cached by
:class:`~probecommit.tasks.base.CachedSimulator`. One DIRECT client per simulator object.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.engines.cache import InstanceCache

from probecommit.engines.pybullet import disconnect, import_pybullet, mm_dynamics, new_client
from probecommit.tasks.base import NoisySimulator
from probecommit.tasks.push2d.sim_mujoco import (
    BOX_HALF_M,
    CHUNK_STEPS,
    MAX_TIME_S,
    SETTLE_S,
    STOP_CHUNKS,
    STOP_SPEED,
    TIMESTEP_S,
)

#: Mass of each massless-in-MuJoCo carriage link (kg), small against the box's 0.5-1.5 kg.
CARRIAGE_MASS_KG = 1e-4
GRAVITY = 9.81
#: Contact settings for a 10 cm box: PyBullet's metre-scale defaults, with the
#: deterministic broadphase of the insertion scenes.
PHYSICS = {"deterministicOverlappingPairs": 1, "numSolverIterations": 50}
MODEL_CACHE_SIZE = 16


class PybulletPush2DSimulator(NoisySimulator):
    """2-D push ground truth in PyBullet (scene in the module docstring).

    Args:
        noise_sigma: Noise per rest-position component added to each probe reading (m).
    """

    engine = "pybullet"

    def __init__(self, noise_sigma: float = 0.05) -> None:
        super().__init__(noise_sigma)
        self._p = import_pybullet()
        self._clients = InstanceCache(self._build_client, MODEL_CACHE_SIZE,
                                      evict=lambda key, entry: disconnect(entry[0]))
        self._instance = self._clients.get

    def _build_client(self, mu: float, m: float) -> tuple[int, int]:
        """A client holding the plane and the box chain of one ``(mu, m)`` (kept by the LRU ``self._instance``)."""
        p = self._p
        cid = new_client(TIMESTEP_S, PHYSICS)
        p.setGravity(0.0, 0.0, -GRAVITY, physicsClientId=cid)
        plane_shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
        plane = p.createMultiBody(0.0, plane_shape, physicsClientId=cid)
        mm_dynamics(plane, -1, cid, margin=None, lateralFriction=1.0)
        box_shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[BOX_HALF_M] * 3, physicsClientId=cid)
        inertia = [1e-3, 1e-3, 1e-3]
        body = p.createMultiBody(
            baseMass=0.0, basePosition=[0.0, 0.0, 0.0],
            linkMasses=[CARRIAGE_MASS_KG, CARRIAGE_MASS_KG, float(m)],
            linkCollisionShapeIndices=[-1, -1, box_shape], linkVisualShapeIndices=[-1, -1, -1],
            linkPositions=[[0, 0, 0], [0, 0, 0], [0, 0, BOX_HALF_M]], linkOrientations=[[0, 0, 0, 1]] * 3,
            linkInertialFramePositions=[[0, 0, 0]] * 3, linkInertialFrameOrientations=[[0, 0, 0, 1]] * 3,
            linkParentIndices=[0, 1, 2], linkJointTypes=[p.JOINT_PRISMATIC] * 3,
            linkJointAxis=[[1, 0, 0], [0, 1, 0], [0, 0, 1]], physicsClientId=cid,
        )
        for link in range(3):
            mm_dynamics(body, link, cid, margin=None, lateralFriction=float(mu), localInertiaDiagonal=inertia)
            # Free joints: disable the default velocity motors.
            p.setJointMotorControl2(body, link, p.VELOCITY_CONTROL, force=0.0, physicsClientId=cid)
        return cid, body

    def rest(self, mu: float, m: float, k_d: float, jx: float, jy: float) -> np.ndarray:
        """Named query: 2-D displacement (m) of the box after an impulse ``(jx, jy)`` (N s)."""
        p = self._p
        cid, body = self._instance(mu, m)
        for link in range(3):
            p.resetJointState(body, link, 0.0, 0.0, physicsClientId=cid)

        def step(n: int, damp: bool) -> None:
            for _ in range(n):
                if damp:
                    vx = p.getJointState(body, 0, physicsClientId=cid)[1]
                    vy = p.getJointState(body, 1, physicsClientId=cid)[1]
                    p.setJointMotorControlArray(body, [0, 1], p.TORQUE_CONTROL, forces=[-k_d * vx, -k_d * vy],
                                                physicsClientId=cid)
                p.stepSimulation(physicsClientId=cid)

        p.setJointMotorControlArray(body, [0, 1], p.TORQUE_CONTROL, forces=[0.0, 0.0], physicsClientId=cid)
        step(int(round(SETTLE_S / TIMESTEP_S)), damp=False)
        start = np.array([p.getJointState(body, j, physicsClientId=cid)[0] for j in (0, 1)])
        p.resetJointState(body, 0, start[0], jx / m, physicsClientId=cid)
        p.resetJointState(body, 1, start[1], jy / m, physicsClientId=cid)
        quiet = 0
        for _ in range(int(round(MAX_TIME_S / (TIMESTEP_S * CHUNK_STEPS)))):
            step(CHUNK_STEPS, damp=True)
            v = [p.getJointState(body, j, physicsClientId=cid)[1] for j in (0, 1)]
            if np.hypot(*v) < STOP_SPEED:
                quiet += 1
                if quiet >= STOP_CHUNKS:
                    break
            else:
                quiet = 0
        end = np.array([p.getJointState(body, j, physicsClientId=cid)[0] for j in (0, 1)])
        return end - start

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("rest", theta, (float(np.ravel(u)[0]), 0.0))
        return clean + self.noise_sigma * rng.standard_normal(2)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if context is None:
            raise ValueError("the push2d outcome needs the 2-D target (context)")
        rest = self.cached("rest", theta, np.ravel(action))
        return {"realized": float(np.linalg.norm(rest - np.asarray(context, dtype=float).reshape(2)))}

    def close(self) -> None:
        for cid, _ in self._clients.values():
            disconnect(cid)
        self._clients.clear()

    def __del__(self) -> None:  # pragma: no cover - interpreter-dependent
        self.close()
