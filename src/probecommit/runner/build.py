"""Build task models and simulators from a study config (engines imported lazily)."""

from __future__ import annotations

import numpy as np

from probecommit.core.belief import ParticleFilter
from probecommit.core.likelihood import GaussianLikelihood, MixtureLikelihood, TemperedLikelihood
from probecommit.runner.config import BeliefConfig, ModelConfig, SimulatorConfig
from probecommit.tasks.insertion.model import TIP_RADIUS_MM, InsertionModel
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator, InsertionSimulator


def build_model(cfg: ModelConfig) -> InsertionModel:
    """The deployed or corrected insertion model of a config."""
    offset = -TIP_RADIUS_MM if cfg.boundary == "deployed" else cfg.delta
    return InsertionModel(
        boundary_offset=offset,
        variant=cfg.boundary,
        sigma=cfg.sigma,
        margin=cfg.margin,
        prior_low=np.array(cfg.prior_low, dtype=float),
        prior_high=np.array(cfg.prior_high, dtype=float),
    )


def build_filter(model: InsertionModel, cfg: BeliefConfig) -> ParticleFilter:
    """The particle filter of a config, with its likelihood variant."""
    likelihood = GaussianLikelihood(model.sigma)
    if cfg.likelihood == "tempered":
        likelihood = TemperedLikelihood(likelihood, cfg.temperature)
    elif cfg.likelihood == "mixture":
        likelihood = MixtureLikelihood(likelihood, cfg.epsilon, cfg.mixture_low, cfg.mixture_high)
    return ParticleFilter(
        model=model,
        likelihood=likelihood,
        n_particles=cfg.particles,
        resample_fraction=cfg.resample_fraction,
        jitter=cfg.jitter,
        rejuvenation=cfg.rejuvenation,
    )


def build_simulator(cfg: SimulatorConfig) -> InsertionSimulator:
    """The ground-truth simulator of a config; engine modules are imported only here."""
    common = dict(noise_sigma=cfg.noise_sigma, aim_offset=cfg.aim_offset)
    if cfg.engine == "analytic":
        return AnalyticInsertionSimulator(
            boundary_offset=cfg.boundary_offset, capture_scale=cfg.capture_scale, **common
        )
    if cfg.engine == "mujoco":
        from probecommit.tasks.insertion.sim_mujoco import MujocoInsertionSimulator

        return MujocoInsertionSimulator(**common)
    raise NotImplementedError(
        f"engine {cfg.engine!r} has no insertion simulator in this release; use 'mujoco' or 'analytic'"
    )
