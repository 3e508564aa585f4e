"""A learned baseline: a GRU that reads a probe history and commits, trained on expected miss.

The policy sees what the pipeline sees: the probe history ``(u_j, y_j)`` drawn with the
pipeline's schedule (random pulses from the family's probe grid) and the target (the
context). It regresses the 2-D impulse (a bearing and a log-magnitude, squashed into
the range of the pipeline's action grid) and is trained to minimize the *expected miss*
``E ||rest(J(H), theta) - target||`` through a differentiable copy of the analytic model
the belief uses (fitted to the MuJoCo scene before any audit), over truths drawn from
the pipeline's prior and targets from the config's target set. At evaluation its impulse
is snapped to the nearest action of the pipeline's grid, so both commit from the same
action set. (A softmax over the 2805 grid actions trained on the same objective stalled
at 0.47 m expected miss after 600 steps; the regression reaches the analytic optimum's
neighbourhood.) Training data come from the analytic
model, not the engine: it is the model the pipeline itself reasons with, it is exact and
cheap, and using the engine would give the GRU an advantage the pipeline does not have.

PyTorch on CPU (``pip install 'probecommit[gru]'``; torch is imported only here).
Deterministic per seed: NumPy and torch seeded, ``torch.use_deterministic_algorithms``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from probecommit.engines import require
from probecommit.store.safefile import write_text


@dataclass(frozen=True)
class TrainingConfig:
    """How one GRU is trained (frozen in ``configs/paper/gru.yaml``)."""

    budget: int = 5
    hidden: int = 64
    samples: int = 6000
    steps: int = 1500
    batch: int = 256
    learning_rate: float = 3e-3
    threads: int = 1


def encode_history(u: np.ndarray, y: np.ndarray, context: np.ndarray, u_scale: float, y_scale: float) -> np.ndarray:
    """Sequence features ``[E, max(K, 1), p + m + c + 1]`` of probe histories.

    Each step holds the scaled probe, the scaled observation, the scaled target and a
    flag 1; a budget-0 history is one step of zeros with flag 0 and the target, so the
    policy still knows where to aim.

    Args:
        u: ``[E, K, p]`` probes; y: ``[E, K, m]`` observations; context: ``[E, c]`` targets.
        u_scale, y_scale: Divisors that bring probes and observations to order one.
    """
    n_e, k = u.shape[0], u.shape[1]
    c = context.reshape(n_e, -1) / y_scale
    if k == 0:
        zeros = np.zeros((n_e, 1, u.shape[2] + y.shape[2]))
        return np.concatenate([zeros, np.repeat(c[:, None, :], 1, axis=1), np.zeros((n_e, 1, 1))], axis=-1)
    steps = [u / u_scale, y / y_scale, np.repeat(c[:, None, :], k, axis=1), np.ones((n_e, k, 1))]
    return np.concatenate(steps, axis=-1)


def make_training_set(model: Any, contexts: np.ndarray, config: TrainingConfig, seed: int) -> dict[str, np.ndarray]:
    """Histories drawn from the prior, the schedule and the model's noise, with every action's miss.

    Returns:
        ``x`` ``[S, K, F]`` features, ``theta`` ``[S, d]`` truths, ``target`` ``[S, 2]``.
    """
    rng = np.random.default_rng(seed)
    s, k = config.samples, config.budget
    theta = model.sample_prior(rng, s)
    ctx = contexts[rng.integers(len(contexts), size=s)]
    grid = np.asarray(model.probe_grid, dtype=float)
    u = grid[rng.integers(len(grid), size=(s, k))]
    y = np.stack([model.predict(u[:, j], theta[:, None, :])[:, 0, :] for j in range(k)], axis=1)
    y = y + model.sigma * rng.standard_normal(y.shape)
    scales = feature_scales(model)
    return {"x": encode_history(u, y, ctx, *scales).astype(np.float32), "theta": theta.astype(np.float64),
            "target": ctx.astype(np.float64)}


def feature_scales(model: Any) -> tuple[float, float]:
    """Divisors for probes and observations (their largest grid / prior-predicted magnitudes)."""
    u_scale = float(np.max(np.abs(np.asarray(model.probe_grid, dtype=float)))) or 1.0
    return u_scale, 1.0


def action_box(model: Any) -> tuple[float, float, float, float]:
    """Bearing (rad) and log-magnitude ranges of the model's polar action grid."""
    grid = np.asarray(model.action_grid, dtype=float)
    bearing = np.arctan2(grid[:, 1], grid[:, 0])
    log_mag = np.log(np.hypot(grid[:, 0], grid[:, 1]))
    return float(bearing.min()), float(bearing.max()), float(log_mag.min()), float(log_mag.max())


def _network(torch: Any, features: int, hidden: int, box: tuple[float, float, float, float]) -> Any:
    nn = torch.nn
    b_lo, b_hi, m_lo, m_hi = box

    class GRUPolicy(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.gru = nn.GRU(features, hidden, batch_first=True)
            self.head = nn.Sequential(nn.Linear(hidden, hidden), nn.Tanh(), nn.Linear(hidden, 2))

        def forward(self, x):  # [B, K, F] -> [B, 2] impulse (N s) inside the grid's range
            _, h = self.gru(x)
            raw = torch.sigmoid(self.head(h[-1]).double())
            bearing = b_lo + (b_hi - b_lo) * raw[:, 0]
            magnitude = torch.exp(m_lo + (m_hi - m_lo) * raw[:, 1])
            return torch.stack([magnitude * torch.cos(bearing), magnitude * torch.sin(bearing)], dim=-1)

    return GRUPolicy()


def torch_miss(torch: Any, impulse: Any, theta: Any, target: Any, mu_scale: float, g: float = 9.81) -> Any:
    """Differentiable 2-D push miss: the push2d model's closed form in torch (see ``tasks/push2d/model.py``)."""
    mu, m, k_d = mu_scale * theta[:, 0], theta[:, 1], theta[:, 2]
    mag = torch.linalg.vector_norm(impulse, dim=-1)
    x = (mag / m) / (mu * g * m / k_d)
    d = mu * g * (m / k_d) ** 2 * (x - torch.log1p(x))
    rest = d[:, None] * impulse / mag[:, None]
    return torch.linalg.vector_norm(rest - target, dim=-1)


def _seed_everything(torch: Any, seed: int, threads: int) -> None:
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(threads)


def train(data: dict[str, np.ndarray], model: Any, config: TrainingConfig, seed: int,
          progress: Callable[[int, int], None] | None = None) -> tuple[Any, list[float]]:
    """Train one policy on expected miss; returns ``(state_dict, loss curve)``."""
    torch = require("torch")
    _seed_everything(torch, seed, config.threads)
    x = torch.from_numpy(data["x"])
    theta, target = torch.from_numpy(data["theta"]), torch.from_numpy(data["target"])
    net = _network(torch, x.shape[-1], config.hidden, action_box(model))
    opt = torch.optim.Adam(net.parameters(), lr=config.learning_rate)
    gen = torch.Generator().manual_seed(seed)
    curve = []
    for step in range(config.steps):
        idx = torch.randint(0, x.shape[0], (config.batch,), generator=gen)
        loss = torch_miss(torch, net(x[idx]), theta[idx], target[idx], model.mu_scale).mean()  # expected miss
        opt.zero_grad()
        loss.backward()
        opt.step()
        curve.append(float(loss.detach()))
        if progress and (step + 1) % 50 == 0:
            progress(step + 1, config.steps)
    return net.state_dict(), curve


def act(state: Any, x: np.ndarray, model: Any, config: TrainingConfig) -> np.ndarray:
    """The committed action index per history: the grid action nearest the policy's impulse."""
    torch = require("torch")
    _seed_everything(torch, 0, config.threads)
    net = _network(torch, x.shape[-1], config.hidden, action_box(model))
    net.load_state_dict(state)
    with torch.no_grad():
        impulse = net(torch.from_numpy(x.astype(np.float32))).numpy()
    grid = np.asarray(model.action_grid, dtype=float)
    return np.argmin(((impulse[:, None, :] - grid[None, :, :]) ** 2).sum(axis=-1), axis=1)


def train_or_resume(out: Path, data: dict[str, np.ndarray], model: Any, config: TrainingConfig, seed: int,
                    progress: Callable[[int, int], None] | None = None) -> tuple[Any, dict[str, Any]]:
    """Train seed ``seed`` unless its checkpoint exists (an interrupted run resumes per seed)."""
    torch = require("torch")
    path = out / f"seed-{seed:02d}.pt"
    meta_path = out / f"seed-{seed:02d}.json"
    if path.is_file() and meta_path.is_file():
        meta = json.loads(meta_path.read_text())
        if meta.get("config") == asdict(config):
            return torch.load(path, weights_only=True), meta
    state, curve = train(data, model, config, seed, progress)
    out.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".pt.tmp")
    torch.save(state, tmp)
    tmp.replace(path)
    meta = {"seed": seed, "config": asdict(config), "loss_first": curve[0], "loss_last": float(np.mean(curve[-20:]))}
    write_text(meta_path, json.dumps(meta, indent=1))
    return state, meta


def equivalent(difference: tuple[float, float, float], margin: float) -> bool:
    """The pre-registered equivalence test: the difference's interval lies inside ``(-margin, +margin)``."""
    _, lo, hi = difference
    return bool(-margin < lo and hi < margin)
