"""2-D push ground truth in MuJoCo: a box on a plane, struck by an impulse.

Scene (one compiled model per truth ``(mu, m, k_d)``, LRU-cached):

* a ground plane and a 10 cm cube (half-size 5 cm) of mass ``m`` on it; the box has
  three slide joints (x, y, z) and no rotation (the impulse acts through its centre of
  mass, so an ideal box would not turn);
* Coulomb friction ``mu`` on both geoms (MuJoCo takes the larger), ``condim 3`` with
  the **elliptic** friction cone, so friction is isotropic. (Measured: MuJoCo's default
  pyramidal cone makes friction depend on the sliding direction: a push at 45 degrees
  goes 16-29% farther than one along x and bends towards the diagonal, which no
  isotropic analytic model represents);
* linear damping ``k_d`` as joint damping on the x and y slide joints, so
  ``m dv/dt = -k_d v`` plus contact friction, realised by the engine;
* default contact softness (solref 0.02 s, solimp default), timestep 1 ms,
  ``implicitfast`` integrator (joint damping integrated implicitly).

A query resets the data (the box at its start pose), lets the box settle on the
plane for ``SETTLE_S`` with no horizontal velocity, sets the horizontal velocity to
``J / m`` (an impulse) and steps in chunks of ``CHUNK_STEPS`` until the horizontal speed
stays below ``STOP_SPEED`` for ``STOP_CHUNKS`` chunks (or ``MAX_TIME_S``). The answer is
the 2-D displacement from the settled start: a deterministic function of the query,
cached per ``(theta, impulse)`` by :class:`~probecommit.tasks.base.CachedSimulator`.
"""

from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from probecommit.engines import require
from probecommit.engines.cache import InstanceCache
from probecommit.tasks.base import NoisySimulator

BOX_HALF_M = 0.05
TIMESTEP_S = 1e-3
SETTLE_S = 0.2
CHUNK_STEPS = 10
STOP_SPEED = 1e-4  # m/s
STOP_CHUNKS = 3
MAX_TIME_S = 20.0
MODEL_CACHE_SIZE = 64

#: Development truths for the friction fit (not evaluation truths) and the fit's pulses.
FIT_TRUTHS = ((0.3, 1.25, 1.2), (0.5, 0.75, 2.4))
FIT_PULSES = (1.0, 2.0, 3.0)


def _f(x: float) -> str:
    return repr(float(x))


def scene_xml(mu: float, m: float, k_d: float) -> str:
    """MJCF of one truth ``(mu, m, k_d)``."""
    fr = f"{_f(mu)} 0.005 0.0001"
    h = _f(BOX_HALF_M)
    return f"""
<mujoco model="push2d">
  <option timestep="{_f(TIMESTEP_S)}" gravity="0 0 -9.81" integrator="implicitfast" cone="elliptic"/>
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1" friction="{fr}" condim="3"/>
    <body name="box" pos="0 0 {h}">
      <inertial pos="0 0 0" mass="{_f(m)}" diaginertia="1e-3 1e-3 1e-3"/>
      <joint name="x" type="slide" axis="1 0 0" damping="{_f(k_d)}"/>
      <joint name="y" type="slide" axis="0 1 0" damping="{_f(k_d)}"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom name="box" type="box" size="{h} {h} {h}" friction="{fr}" condim="3"/>
    </body>
  </worldbody>
</mujoco>
"""


class MujocoPush2DSimulator(NoisySimulator):
    """2-D push ground truth in MuJoCo (scene in the module docstring).

    Args:
        noise_sigma: Noise per rest-position component added to each probe reading (m).
    """

    engine = "mujoco"

    def __init__(self, noise_sigma: float = 0.05) -> None:
        super().__init__(noise_sigma)
        self._mj = require("mujoco")
        self._instance = InstanceCache(self._compile, MODEL_CACHE_SIZE).get

    def _compile(self, mu: float, m: float, k_d: float) -> tuple[Any, Any]:
        model = self._mj.MjModel.from_xml_string(scene_xml(mu, m, k_d))
        return model, self._mj.MjData(model)

    def rest(self, mu: float, m: float, k_d: float, jx: float, jy: float) -> np.ndarray:
        """Named query: 2-D displacement (m) of the box after an impulse ``(jx, jy)`` (N s)."""
        mj = self._mj
        model, data = self._instance(mu, m, k_d)
        mj.mj_resetData(model, data)
        mj.mj_step(model, data, nstep=int(round(SETTLE_S / TIMESTEP_S)))
        start = data.qpos[:2].copy()
        data.qvel[0] = jx / m
        data.qvel[1] = jy / m
        quiet = 0
        for _ in range(int(round(MAX_TIME_S / (TIMESTEP_S * CHUNK_STEPS)))):
            mj.mj_step(model, data, nstep=CHUNK_STEPS)
            if np.hypot(data.qvel[0], data.qvel[1]) < STOP_SPEED:
                quiet += 1
                if quiet >= STOP_CHUNKS:
                    break
            else:
                quiet = 0
        return data.qpos[:2] - start

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("rest", theta, (float(np.ravel(u)[0]), 0.0))
        return clean + self.noise_sigma * rng.standard_normal(2)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if context is None:
            raise ValueError("the push2d outcome needs the 2-D target (context)")
        rest = self.cached("rest", theta, np.ravel(action))
        return {"realized": float(np.linalg.norm(rest - np.asarray(context, dtype=float).reshape(2)))}


def fit_friction_scale(
    simulator: MujocoPush2DSimulator | None = None,
    truths: Iterable[Iterable[float]] = FIT_TRUTHS,
    pulses: Iterable[float] = FIT_PULSES,
) -> dict[str, Any]:
    """Fit the analytic model's effective-friction factor ``kappa`` to the engine.

    Least squares of the noise-free engine slide distances of pulses along +x on the
    development truths against ``stop_distance(J, kappa mu, m, k_d)``; a 1-D bounded
    search (golden section on [0.8, 1.2], 1e-7 tolerance). Uses no evaluation instance
    and no outcome.

    Returns:
        ``{"mu_scale": kappa, "rms_before": ..., "rms_after": ..., "n": readings}`` (metres).
    """
    from probecommit.tasks.push1d.model import stop_distance

    sim = simulator if simulator is not None else MujocoPush2DSimulator(noise_sigma=0.0)
    rows = [(tuple(map(float, th)), float(j)) for th in truths for j in pulses]
    engine = np.array([float(sim.cached("rest", th, (j, 0.0))[0]) for th, j in rows])
    th = np.array([r[0] for r in rows])
    jj = np.array([r[1] for r in rows])

    def rms(kappa: float) -> float:
        return float(np.sqrt(np.mean((stop_distance(jj, kappa * th[:, 0], th[:, 1], th[:, 2]) - engine) ** 2)))

    lo, hi = 0.8, 1.2
    phi = (np.sqrt(5.0) - 1) / 2
    a, b = hi - phi * (hi - lo), lo + phi * (hi - lo)
    fa, fb = rms(a), rms(b)
    while hi - lo > 1e-7:
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - phi * (hi - lo)
            fa = rms(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + phi * (hi - lo)
            fb = rms(b)
    kappa = (lo + hi) / 2
    return {"mu_scale": kappa, "rms_before": rms(1.0), "rms_after": rms(kappa), "n": len(rows)}
