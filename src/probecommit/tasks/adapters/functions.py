"""A family from plain functions: ``predict(latents, probe) -> reading`` and
``loss(latents, action, context) -> loss``, a prior box and grids.

The functions are called on broadcast NumPy arrays, so ordinary arithmetic on
``latents[..., i]``, ``probe[..., j]`` and ``action[..., j]`` works as written for one value:

* ``predict(latents[E, N, d], probe[E, 1, p]) -> [E, N]`` (one reading) or ``[E, N, m]``;
* ``loss(latents[E, 1, N, d], action[1, A, 1, a], context[E, 1, 1, c] or None) -> [E, A, N]``:
  failures (0/1) for ``kind="binary"``, else a miss >= 0, which the model divides by the margin.

The family's ``analytic`` simulator evaluates the same functions at the truth (plus reading
noise); give ``simulators`` to use a real engine for the ground truth instead.
"""

from __future__ import annotations

from typing import Any, Callable, Literal, Mapping, Sequence

import numpy as np

from probecommit.tasks.base import TaskSpec
from probecommit.tasks.declare import Context, Declaration, DeclaredModel, Latent, family


def function_family(name: str, *, latents: Sequence[Latent], predict: Callable[..., Any], loss: Callable[..., Any],
                    probe_grid: Any, action_grid: Any, sigma: float, kind: Literal["binary", "continuous"] = "continuous",
                    contexts: Sequence[Context] = (), decision: str | None = None, margin: float = 1.0,
                    noise_sigma: float | None = None, simulators: Mapping[str, str] | None = None,
                    summary: Mapping[str, str] | None = None, register: bool = True) -> TaskSpec:
    """Declare and register a family from two functions (see the module docstring for shapes).

    Returns:
        The registered :class:`TaskSpec` (check it with :func:`probecommit.check_family`).
    """
    decl = Declaration(name=name, latents=tuple(latents), probe_grid=probe_grid, action_grid=action_grid, loss=kind,
                       sigma=sigma, decision=decision, contexts=tuple(contexts), margin=margin, noise_sigma=noise_sigma,
                       simulators=dict(simulators or {}), summary=dict(summary or {}))

    def model_predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        y = np.asarray(predict(theta, np.asarray(u, dtype=float)[:, None, :]), dtype=float)
        y = np.broadcast_to(y, theta.shape[:2]) if y.ndim < theta.ndim else y
        return y[..., None] if y.ndim == theta.ndim - 1 else y

    def model_loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        ctx = None if context is None else np.asarray(context, dtype=float)[:, None, None, :]
        out = np.asarray(loss(theta[:, None, :, :], np.asarray(actions, dtype=float)[None, :, None, :], ctx))
        out = np.broadcast_to(out, (theta.shape[0], np.asarray(actions).shape[0], theta.shape[1]))
        return out.astype(bool) if self.binary_loss else out.astype(float) / self.margin

    model = type(f"{name}_model", (DeclaredModel,), {"predict": model_predict, "loss": model_loss,
                                                     "__doc__": f"Model of the function family {name!r}."})
    return family(decl, model, register=register)
