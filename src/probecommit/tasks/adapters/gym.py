"""A family from a Gymnasium environment whose latent physics is set through ``reset(options=...)``.

The environment is the ground truth (engine ``gymnasium``); probing and committing are both
actions held for a fixed number of steps:

* ``env.reset(seed=seed, options={"latents": {name: value, ...}})`` sets the physics (a
  mass, a damping) and starts an episode; the environment must apply the latents there
  (Gymnasium's own environments do not: wrap one in a ``gymnasium.Wrapper`` whose ``reset``
  writes them into the simulator, as ``examples/gym_reacher_family.py`` does);
* a probe ``u`` steps ``command(u)`` for ``steps`` steps (or until the episode ends) and reads
  ``measure(first_obs, last_obs, info)`` plus noise;
* a commit ``a`` does the same with ``command(a)``; its realized loss is ``loss(value, context)``
  of the measured value (a miss >= 0, or failure for ``kind="binary"``).

The belief needs the reading of many particles at once, which an environment cannot give
cheaply, so the family's *model* is a surrogate: the environment's measurements tabulated
once per process on a lattice of ``lattice`` points per latent over the prior box (for every
probe and every action) and interpolated multilinearly. The surrogate's error is the model's
misspecification, exactly as an analytic model's would be, and the audit measures its effect.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Literal, Sequence

import numpy as np

from probecommit.tasks.base import NoisySimulator, TaskSpec
from probecommit.tasks.declare import Context, Declaration, DeclaredModel, Latent, family


@dataclass(frozen=True, eq=False)
class GymProtocol:
    """How a family talks to its environment (see the module docstring).

    Attributes:
        make_env: Builds the environment (called once per simulator and once for the surrogate).
        measure: ``measure(first_obs, last_obs, info) -> value`` (a float or a vector).
        loss: ``loss(value[..., m], context[..., c] or None) -> loss[...]``, vectorized (NumPy).
        steps: Steps a probe or a commit holds its action.
        command: Maps a probe or an action ``[p]`` to the environment's action (default: as is).
        seed: The reset seed (the same for every rollout, so a rollout is a pure function of
            the latents and the action).
    """

    make_env: Callable[[], Any]
    measure: Callable[[Any, Any, dict], Any]
    loss: Callable[[np.ndarray, np.ndarray | None], np.ndarray]
    steps: int
    command: Callable[[np.ndarray], Any] = np.asarray
    seed: int = 0


def rollout(env: Any, protocol: GymProtocol, names: Sequence[str], theta: Sequence[float], action: np.ndarray) -> np.ndarray:
    """Reset ``env`` at the latents ``theta``, hold ``action`` for ``protocol.steps`` steps, measure."""
    first, info = env.reset(seed=protocol.seed, options={"latents": {n: float(v) for n, v in zip(names, theta)}})
    last = first
    command = protocol.command(np.asarray(action, dtype=float))
    for _ in range(protocol.steps):
        last, _, terminated, truncated, info = env.step(command)
        if terminated or truncated:
            break
    return np.atleast_1d(np.asarray(protocol.measure(first, last, info), dtype=float))


def interpolate(table: np.ndarray, low: np.ndarray, high: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Multilinear interpolation of ``table[L1, ..., Ld, *rest]`` on the lattice over ``[low, high]``
    at ``theta[..., d]`` (clipped to the box): ``[..., *rest]``."""
    d = low.shape[0]
    sizes = np.array(table.shape[:d])
    pos = np.clip((np.asarray(theta, float) - low) / (high - low), 0.0, 1.0) * (sizes - 1)
    base = np.minimum(np.floor(pos).astype(int), sizes - 2)
    frac = pos - base
    out = 0.0
    for corner in itertools.product((0, 1), repeat=d):
        bits = np.array(corner)
        weight = np.prod(np.where(bits == 1, frac, 1.0 - frac), axis=-1)
        index = tuple((base + bits)[..., i] for i in range(d))
        value = table[index]
        out = out + weight.reshape(weight.shape + (1,) * (value.ndim - weight.ndim)) * value
    return out


_TABLES: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def _tables(decl: Declaration, protocol: GymProtocol, lattice: int, low: np.ndarray, high: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """The environment's measurements on the lattice: ``(probes [L..., P, m], actions [L..., A, m])``, once per process."""
    key = (decl.name, id(protocol), lattice, tuple(low), tuple(high))
    if key not in _TABLES:
        env = protocol.make_env()
        axes = [np.linspace(lo, hi, lattice) for lo, hi in zip(low, high)]
        points = list(itertools.product(*axes))
        probes, actions = decl.probes(), decl.actions()

        def grid(commands: np.ndarray) -> np.ndarray:
            values = np.array([[rollout(env, protocol, decl.latent_names, theta, c) for c in commands] for theta in points])
            return values.reshape((lattice,) * len(axes) + values.shape[1:])

        _TABLES[key] = (grid(probes), grid(actions))
        env.close()
    return _TABLES[key]


def _grid_index(values: np.ndarray, grid: np.ndarray, what: str) -> np.ndarray:
    hit = np.abs(values[:, None, :] - grid[None, :, :]).max(axis=2)
    index = hit.argmin(axis=1)
    if np.any(hit[np.arange(len(values)), index] > 1e-9):
        raise ValueError(f"a {what} off the family's grid (the surrogate is tabulated on the grid only)")
    return index


class GymSurrogateModel(DeclaredModel):
    """The surrogate model of a Gymnasium family (module docstring); ``protocol`` and ``lattice`` set per family."""

    protocol: ClassVar[GymProtocol]
    lattice: ClassVar[int]

    def _tables(self) -> tuple[np.ndarray, np.ndarray]:
        return _tables(self.declaration, self.protocol, self.lattice, self.prior_low, self.prior_high)

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        probes, _ = self._tables()
        index = _grid_index(np.asarray(u, float), self.probe_grid, "probe")
        values = interpolate(probes, self.prior_low, self.prior_high, np.asarray(theta, float))  # [E, N, P, m]
        return np.take_along_axis(values, index[:, None, None, None], axis=2)[:, :, 0, :]

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        _, outcomes = self._tables()
        index = _grid_index(np.asarray(actions, float), self.action_grid, "action")
        values = interpolate(outcomes, self.prior_low, self.prior_high, np.asarray(theta, float))[:, :, index, :]
        ctx = None if context is None else np.asarray(context, float)[:, None, None, :]
        out = np.asarray(self.protocol.loss(values, ctx)).transpose(0, 2, 1)  # [E, N, A] -> [E, A, N]
        return out.astype(bool) if self.binary_loss else out.astype(float) / self.margin


class GymSimulator(NoisySimulator):
    """Ground truth of a Gymnasium family: the environment itself, one rollout per distinct query."""

    engine = "gymnasium"
    thread_safe = False  # one environment instance per simulator, stepped in place
    family = "?"
    declaration: ClassVar[Declaration]
    protocol: ClassVar[GymProtocol]

    def __init__(self, noise_sigma: float) -> None:
        super().__init__(noise_sigma)
        self._env = None
        self._d = len(self.declaration.latents)

    def rollout(self, *values: float) -> np.ndarray:
        if self._env is None:
            self._env = self.protocol.make_env()
        return rollout(self._env, self.protocol, self.declaration.latent_names, values[:self._d], np.asarray(values[self._d:]))

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached("rollout", theta, np.ravel(u))
        return clean + self.noise_sigma * rng.standard_normal(clean.shape[0])

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if self.declaration.contexts and context is None:
            raise ValueError(f"the {self.family} outcome needs the context ({', '.join(self.declaration.context_names)})")
        value = self.cached("rollout", theta, np.ravel(action))
        ctx = None if context is None else np.asarray(context, float).reshape(-1)
        loss = float(np.asarray(self.protocol.loss(value, ctx)).reshape(-1)[0])
        return {"realized": loss, "measured": value.tolist()}


def gym_family(name: str, *, protocol: GymProtocol, latents: Sequence[Latent], probe_grid: Any, action_grid: Any,
               sigma: float, kind: Literal["binary", "continuous"] = "continuous", contexts: Sequence[Context] = (),
               decision: str | None = None, margin: float = 1.0, noise_sigma: float | None = None, lattice: int = 17,
               summary: dict[str, str] | None = None, register: bool = True) -> TaskSpec:
    """Declare and register a family whose ground truth is a Gymnasium environment (module docstring).

    Args:
        lattice: Surrogate lattice points per latent (``lattice ** d`` x (probes + actions) rollouts,
            once per process).
    """
    if lattice < 2:
        raise ValueError(f"gym family {name!r}: lattice must be >= 2, got {lattice}")
    decl = Declaration(name=name, latents=tuple(latents), probe_grid=probe_grid, action_grid=action_grid, loss=kind,
                       sigma=sigma, decision=decision, contexts=tuple(contexts), margin=margin, noise_sigma=noise_sigma,
                       summary={"probe": "held action / measure", "action": "held action", **(summary or {})},
                       analytic=False, simulators={})
    simulator = type(f"{name}_gymnasium", (GymSimulator,), {"declaration": decl, "protocol": protocol, "family": name})
    decl = Declaration(**{**decl.__dict__, "simulators": {"gymnasium": simulator}})
    simulator.declaration = decl
    model = type(f"{name}_surrogate", (GymSurrogateModel,), {"protocol": protocol, "lattice": int(lattice)})
    return family(decl, model, register=register)
