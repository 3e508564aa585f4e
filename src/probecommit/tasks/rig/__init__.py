"""Tool insertion into a machined pocket by touch, at rig scale (paper Sec. V-D, Table IX).

Registers the ``rig`` family: the insertion model with every length at 3.86x, a
touch-switch tap that reads the block top or "through the opening", a 5.9 mm tool,
and the model's window as the realized-failure criterion. Its simulators (MuJoCo and
analytic) write the same session logs a physical rig does (``probecommit.robot``).
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from probecommit.tasks.declare import Declaration, Latent, family
from probecommit.tasks.rig.config import RIG_BOX_LIMIT_MM, RigConfigHooks, RigModelChecks
from probecommit.tasks.rig.model import DESCENT_STEP_MM, PRIOR_HIGH, PRIOR_LOW, TOOL_RADIUS_MM, RigModel, rig_half_gap


def build_model(config) -> RigModel:  # noqa: ANN001 - the derived config
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


DECLARATION = Declaration(
    name="rig",
    latents=(Latent("x_hole", "mm", PRIOR_LOW[0], PRIOR_HIGH[0]), Latent("c", "", PRIOR_LOW[1], PRIOR_HIGH[1])),
    probe_grid=RigModel.probe_grid, action_grid=RigModel.action_grid,
    loss="binary", sigma=DESCENT_STEP_MM, sigma_limit=1000, decision="x_hole", noise_sigma=0.0,
    #: The injected boundary fault: the through-the-opening boundary moved inward by that many mm (0 = as deployed).
    model_fields={"boundary_pull_in": (float, Field(0.0, ge=-20, le=40))},
    simulator_fields={
        #: Probability that the switch reports the other outcome (a bounce on the edge, a late close).
        "misread_rate": (float, Field(0.01, ge=0, lt=1)),
        #: The frame fault.
        "aim_offset": (float, Field(0.0, ge=-RIG_BOX_LIMIT_MM, le=RIG_BOX_LIMIT_MM)),
    },
    simulators={
        "analytic": "probecommit.tasks.rig.sim_base:AnalyticRigSimulator",
        "mujoco": "probecommit.tasks.rig.sim_mujoco:MujocoRigSimulator",
    },
    analytic=False, engines_open=True, default_engine="mujoco",
    model_base=RigModelChecks, config_base=RigConfigHooks,
    summary={"probe": "touch tap", "action": "aim", "sigma": "0.5 mm", "budgets": "1-5",
             "metric": "failure (window)", "n": "12 x 10"},
    example={"belief": {"likelihood": "mixture", "epsilon": 0.03, "mixture_low": -12.0, "mixture_high": 2.0}},
    figure_guides=lambda model: {"half_gap": float(rig_half_gap(1.0))},
    doc="Tool insertion into a machined pocket by touch, at rig scale (paper Sec. V-D).",
)
SPEC = family(DECLARATION, RigModel, build_model=build_model)
