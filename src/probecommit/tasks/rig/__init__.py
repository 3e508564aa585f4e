"""Tool insertion into a machined pocket by touch, at rig scale (paper Sec. V-D, Table IX).

Registers the ``rig`` family: the insertion model with every length at 3.86x, a
touch-switch tap that reads the block top or "through the opening", a 5.9 mm tool,
and the model's window as the realized-failure criterion. Its simulators (MuJoCo and
analytic) write the same session logs a physical rig does (``probecommit.robot``).
"""

from __future__ import annotations

import numpy as np

from probecommit.tasks.base import TaskSpec
from probecommit.tasks.registry import register
from probecommit.tasks.rig.config import RigConfig
from probecommit.tasks.rig.model import TOOL_RADIUS_MM, RigModel, rig_half_gap


def build_model(config: RigConfig) -> RigModel:
    """The rig model of a config; ``boundary_pull_in > 0`` is the boundary fault."""
    cfg = config.model
    pulled = cfg.boundary_pull_in != 0
    return RigModel(
        boundary_offset=-TOOL_RADIUS_MM - cfg.boundary_pull_in,
        variant=f"boundary-{cfg.boundary_pull_in:g}mm" if pulled else "deployed",
        sigma=cfg.sigma,
        margin=cfg.margin,
        prior_low=np.array(cfg.prior_low, dtype=float),
        prior_high=np.array(cfg.prior_high, dtype=float),
    )


SPEC = register(
    TaskSpec(
        name="rig",
        config=RigConfig,
        build_model=build_model,
        simulators={
            "analytic": "probecommit.tasks.rig.sim_base:AnalyticRigSimulator",
            "mujoco": "probecommit.tasks.rig.sim_mujoco:MujocoRigSimulator",
        },
        summary={
            "latents": "x_hole, c",
            "probe": "touch tap",
            "action": "aim",
            "sigma": "0.5 mm",
            "budgets": "1-5",
            "metric": "failure (window)",
            "n": "12 x 10",
        },
        example={"belief": {"likelihood": "mixture", "epsilon": 0.03, "mixture_low": -12.0, "mixture_high": 2.0}},
        figure_guides=lambda model: {"half_gap": float(rig_half_gap(1.0))},
    )
)
