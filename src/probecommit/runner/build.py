"""Build task models, filters and simulators from a study config, through the registry.

Engines are imported lazily: only when a simulator of that engine is built.
"""

from __future__ import annotations

from typing import Any, Callable, Iterable

from probecommit.accel import production
from probecommit.core.belief import ParticleFilter
from probecommit.core.executors import BlindBayes, BlindRobust, Executor, ProbeRobust
from probecommit.core.likelihood import GaussianLikelihood, MixtureLikelihood, TemperedLikelihood
from probecommit.runner.config import BeliefConfig, StudyConfig
from probecommit.runner.seeding import blind_rng
from probecommit.tasks import registry


def build_model(config: StudyConfig) -> Any:
    """The family's analytic model of a study config."""
    return registry.build_model(config.task)


def build_filter(model: Any, cfg: BeliefConfig) -> ParticleFilter:
    """The particle filter of a config, with its likelihood variant and the production kernels."""
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
        kernels=production().filter,
    )


def simulator_class(config: StudyConfig) -> type:
    """The class of a study's simulator (its engine module is imported, nothing is built)."""
    return registry.simulator_class(config.family, config.task.simulator.engine)


def build_simulator(config: StudyConfig) -> Any:
    """The ground-truth simulator of a study config (its engine is imported only here)."""
    return registry.build_simulator(config.family, config.task)


def blind_bayes_executor(model: Any, seed: int, n_samples: int) -> BlindBayes:
    """Blind-Bayes over a large fixed prior sample drawn from the study's blind stream."""
    return BlindBayes(model, model.sample_prior(blind_rng(seed), n_samples))


#: The executors a config's ``methods`` names, in the episode table's order (blind ones first):
#: each builder takes (model, plateau, seed, blind prior samples).
EXECUTORS: dict[str, Callable[[Any, str, int, int], Executor]] = {
    "blind_bayes": lambda model, plateau, seed, n: blind_bayes_executor(model, seed, n),
    "blind_robust": lambda model, plateau, seed, n: BlindRobust(model, plateau, production().sets),
    "probe_robust": lambda model, plateau, seed, n: ProbeRobust(model, plateau, production().sets),
}


def build_executors(methods: Iterable[str], model: Any, plateau: str = "prefix", seed: int = 0,
                    blind_prior_samples: int = 0) -> list[Executor]:
    """The executors named by ``methods``, built once and injected into ``runner.inference.commit``.

    Args:
        plateau: The set executors' set at ``t = 1`` (``core.executors.ProbeRobust``).
        seed, blind_prior_samples: The study seed and sample size of Blind-Bayes's prior sample.
    """
    methods = set(methods)
    unknown = methods - set(EXECUTORS)
    if unknown:
        raise ValueError(f"no executor named {sorted(unknown)[0]!r}; known: {', '.join(EXECUTORS)}")
    return [make(model, plateau, seed, blind_prior_samples) for name, make in EXECUTORS.items() if name in methods]


def config_executors(config: StudyConfig, model: Any, methods: Iterable[str] | None = None,
                     plateau: str = "prefix") -> list[Executor]:
    """:func:`build_executors` of a study config (its methods, seed and prior sample size).

    ``plateau`` is the paper's ``prefix`` for a run and a replay; calibration passes its
    ``calibration.plateau`` (that section says how *calibration* constructs the set at t = 1).
    """
    return build_executors(config.methods if methods is None else methods, model, plateau, config.seed,
                           config.blind_prior_samples)
