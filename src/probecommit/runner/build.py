"""Build task models, filters and simulators from a study config, through the registry.

Engines are imported lazily: only when a simulator of that engine is built.
"""

from __future__ import annotations

from typing import Any

from probecommit.core.belief import ParticleFilter
from probecommit.core.likelihood import GaussianLikelihood, MixtureLikelihood, TemperedLikelihood
from probecommit.runner.config import BeliefConfig, StudyConfig
from probecommit.tasks import registry


def build_model(config: StudyConfig) -> Any:
    """The family's analytic model of a study config."""
    return registry.build_model(config.task)


def build_filter(model: Any, cfg: BeliefConfig) -> ParticleFilter:
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
        move=cfg.move,
        move_steps=cfg.move_steps,
    )


def simulator_class(config: StudyConfig) -> type:
    """The class of a study's simulator (its engine module is imported, nothing is built)."""
    return registry.simulator_class(config.family, config.task.simulator.engine)


def build_simulator(config: StudyConfig) -> Any:
    """The ground-truth simulator of a study config (its engine is imported only here)."""
    return registry.build_simulator(config.family, config.task)
