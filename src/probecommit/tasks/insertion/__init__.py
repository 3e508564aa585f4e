"""Peg insertion after surface taps (paper Sec. III): the primary testbed.

Registers the ``insertion`` family: latents ``(x_hole, c)``, a tap probe at one of
nine positions reading the plate top or the pocket floor, and one aim on a 0.5 mm
grid with a binary capture-window loss.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from probecommit.tasks.declare import Declaration, Latent, family
from probecommit.tasks.insertion.config import BOX_LIMIT_MM, InsertionConfigHooks, InsertionModelChecks
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, PRIOR_HIGH, PRIOR_LOW, TIP_RADIUS_MM, InsertionModel


def build_model(config) -> InsertionModel:  # noqa: ANN001 - the derived config
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


DECLARATION = Declaration(
    name="insertion",
    latents=(Latent("x_hole", "mm", PRIOR_LOW[0], PRIOR_HIGH[0]), Latent("c", "", PRIOR_LOW[1], PRIOR_HIGH[1])),
    probe_grid=InsertionModel.probe_grid, action_grid=InsertionModel.action_grid,
    loss="binary", sigma=0.5, sigma_limit=1000, decision="x_hole",
    model_fields={
        "boundary": (Literal["deployed", "corrected"], "deployed"),
        "delta": (float, Field(PAPER_DELTA_MM, ge=-5, le=5)),
    },
    model_order=("boundary", "delta", "sigma", "margin", "prior_low", "prior_high"),
    simulator_fields={
        "aim_offset": (float, Field(0.0, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)),
        #: Analytic engine only: its tap boundary offset and capture scale.
        "boundary_offset": (float, Field(PAPER_DELTA_MM, ge=-BOX_LIMIT_MM, le=BOX_LIMIT_MM)),
        "capture_scale": (float, Field(1.0, gt=0, le=100)),
    },
    simulators={
        "analytic": "probecommit.tasks.insertion.sim_base:AnalyticInsertionSimulator",
        "mujoco": "probecommit.tasks.insertion.sim_mujoco:MujocoInsertionSimulator",
        "pybullet": "probecommit.tasks.insertion.sim_pybullet:PybulletInsertionSimulator",
        "sapien": "probecommit.tasks.insertion.sim_sapien:SapienInsertionSimulator",
    },
    analytic=False, engines_open=True, default_engine="mujoco",
    model_base=InsertionModelChecks, config_base=InsertionConfigHooks,
    summary={"probe": "tap", "action": "aim", "sigma": "0.5 mm", "budgets": "1-8, cover",
             "metric": "failure", "n": "96 x 4"},
    default=True,
    replay_shorthands={"model": "boundary", "delta": "delta", "model_default": "corrected"},
    doc="Peg insertion after surface taps (paper Sec. III).",
)
SPEC = family(DECLARATION, InsertionModel, build_model=build_model)


def make_simulator(engine: str = "mujoco", **fields):
    """An insertion simulator of ``engine`` with simulator-section ``fields`` (validated)."""
    from pydantic import ValidationError

    from probecommit.tasks.config import ConfigError
    from probecommit.tasks.registry import build_simulator

    section = SPEC.config.model_fields["simulator"].annotation
    try:
        config = SPEC.config(simulator=section(engine=engine, **fields))
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"])
        raise ConfigError(f"invalid simulator setting '{field}': {first['msg'].removeprefix('Value error, ')}") from None
    return build_simulator("insertion", config)
