"""The task contracts: an analytic TaskModel and an engine Simulator.

A task never owns an engine. The model is NumPy only and vectorized over
particles; the simulator answers named queries against ground truth. Rollout
(simulator) and inference (model) are separate: runs store every probe, and
beliefs are recomputed from stored probes.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class TaskModel(Protocol):
    """Analytic model of one task family.

    Attributes:
        name: Family name (``"insertion"``).
        variant: Model variant label stored in episode tables (``"deployed"``).
        latent_names: Names of the latent coordinates, in column order.
        prior_low, prior_high: Box prior ``[d]``.
        jitter_scale: Post-resampling jitter standard deviations ``[d]``.
        sigma: Observation noise the likelihood assumes.
        probe_grid: Admissible probes ``[P]``.
        action_grid: Admissible commit actions ``[A]``.
        binary_loss: True when the loss is failure (0/1), False for a continuous miss.
        decision_domain_width: ``D``, width of the decision coordinate's domain.
    """

    name: str
    variant: str
    latent_names: tuple[str, ...]
    prior_low: np.ndarray
    prior_high: np.ndarray
    jitter_scale: np.ndarray
    sigma: float
    probe_grid: np.ndarray
    action_grid: np.ndarray
    binary_loss: bool
    decision_domain_width: float

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Noise-free observation ``[E, N, m]`` for probes ``u[E]`` and ``theta[E, N, d]``."""

    def loss(self, actions: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Modeled loss ``[E, A, N]`` (bool failures when ``binary_loss``)."""

    def decision(self, theta: np.ndarray) -> np.ndarray:
        """Decision coordinate ``z(theta)``: ``[..., d] -> [...]``."""


@runtime_checkable
class Simulator(Protocol):
    """Ground-truth side of one task family in one engine.

    ``probe`` returns a noisy reading drawn with the episode's generator;
    ``execute`` commits an action once and returns the realized outcome, with at
    least the key ``"realized"`` (failure 0/1 or miss).
    """

    engine: str

    def probe(self, theta: np.ndarray, u: float, rng: np.random.Generator) -> np.ndarray: ...

    def execute(self, theta: np.ndarray, action: float) -> dict[str, Any]: ...
