"""Peg insertion after surface taps (paper Sec. III): the primary testbed.

Registers the ``insertion`` family: latents ``(x_hole, c)``, a tap probe at one of
nine positions reading the plate top or the pocket floor, and one aim on a 0.5 mm
grid with a binary capture-window loss.
"""

from __future__ import annotations

import numpy as np

from probecommit.tasks.base import TaskSpec
from probecommit.tasks.insertion.config import InsertionConfig
from probecommit.tasks.insertion.model import TIP_RADIUS_MM, InsertionModel
from probecommit.tasks.registry import register


def build_model(config: InsertionConfig) -> InsertionModel:
    """The deployed or corrected insertion model of a config."""
    cfg = config.model
    offset = -TIP_RADIUS_MM if cfg.boundary == "deployed" else cfg.delta
    return InsertionModel(
        boundary_offset=offset,
        variant=cfg.boundary,
        sigma=cfg.sigma,
        margin=cfg.margin,
        prior_low=np.array(cfg.prior_low, dtype=float),
        prior_high=np.array(cfg.prior_high, dtype=float),
    )


SPEC = register(
    TaskSpec(
        name="insertion",
        config=InsertionConfig,
        build_model=build_model,
        simulators={
            "analytic": "probecommit.tasks.insertion.sim_base:AnalyticInsertionSimulator",
            "mujoco": "probecommit.tasks.insertion.sim_mujoco:MujocoInsertionSimulator",
            "pybullet": "probecommit.tasks.insertion.sim_pybullet:PybulletInsertionSimulator",
            "sapien": "probecommit.tasks.insertion.sim_sapien:SapienInsertionSimulator",
        },
        summary={
            "latents": "x_hole, c",
            "probe": "tap",
            "action": "aim",
            "sigma": "0.5 mm",
            "budgets": "1-8, cover",
            "metric": "failure",
            "n": "96 x 4",
        },
        default=True,
        replay_shorthands={"model": "boundary", "delta": "delta", "model_default": "corrected"},
    )
)


def make_simulator(engine: str = "mujoco", **fields):
    """An insertion simulator of ``engine`` with simulator-section ``fields`` (validated)."""
    from pydantic import ValidationError

    from probecommit.tasks.config import ConfigError
    from probecommit.tasks.insertion.config import InsertionSimulatorConfig
    from probecommit.tasks.registry import build_simulator

    try:
        config = InsertionConfig(simulator=InsertionSimulatorConfig(engine=engine, **fields))
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"])
        raise ConfigError(f"invalid simulator setting '{field}': {first['msg'].removeprefix('Value error, ')}") from None
    return build_simulator("insertion", config)
