"""2-D push (paper Table II, MuJoCo): a box on a plane struck to stop at a 2-D target.

Registers ``push2d``. Every choice (the paper gives latents, probe/action kind, sigma,
budgets and the 3 x 6 instance set size, nothing else):

* **Latents and prior** ``(mu, m, k_d)``: as the 1-D push, ``U[0.2, 0.6]``,
  ``U[0.5, 1.5]`` kg, ``U[0.5, 3.0]`` N s/m; jitter ``(0.01, 0.025, 0.06)``.
* **Scene** (:mod:`probecommit.tasks.push2d.sim_mujoco`): a 10 cm cube on a plane,
  slide joints x/y/z (no rotation), friction ``mu`` with the elliptic cone, linear
  damping ``k_d`` as joint damping on x and y, 1 ms step, implicitfast.
* **Analytic model**: the 1-D closed form along the impulse's direction with one
  fitted effective-friction factor ``kappa = 1.0019`` (``model.mu_scale``), fitted by
  least squares on 6 noise-free engine slides (pulses 1, 2, 3 N s along +x) of two
  development truths ``(0.3, 1.25, 1.2)`` and ``(0.5, 0.75, 2.4)``, none of them an
  evaluation truth, before any study ran.
* **Probe**: a known pulse ``{1, 2, 3}`` N s along +x, reading the 2-D rest position,
  ``sigma = 5`` cm per component (model and simulator); every probe starts from the
  box's start pose.
* **Action**: a 2-D impulse on a polar grid, bearings -30..40 deg in 5 deg steps x
  magnitudes ``0.25 * 1.02^i`` up to 10 N s (15 x 187 = 2805); **context**: the 2-D
  target; **loss**: Euclidean miss (m), divided by the margin ``gamma``.
* **Instances** (``configs/paper/push2d.yaml``): 3 truths ``(0.25, 0.625, 0.8125)``,
  ``(0.4, 1.0, 1.75)``, ``(0.55, 1.375, 2.6875)`` (the diagonal of the 1-D grid) x 6
  targets at ranges ``{0.5, 1.0, 1.5}`` m and bearings ``{-20, +30}`` deg; 6 seeds;
  budgets 0, 2, 5.
* **Decision coordinate**: ``mu`` (latent 0), domain width 0.4.
"""

from __future__ import annotations

from pydantic import Field

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.push1d.model import PRIOR_HIGH, PRIOR_LOW
from probecommit.tasks.push2d.model import FITTED_MU_SCALE, Push2DModel

DECLARATION = Declaration(
    name="push2d",
    latents=(Latent("mu", "", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("m", "kg", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True),
             Latent("k_d", "N s/m", PRIOR_LOW[2], PRIOR_HIGH[2], positive=True)),
    probe_grid=Push2DModel.probe_grid, action_grid=Push2DModel.action_grid,
    loss="continuous", sigma=0.05, sigma_limit=10, decision="mu",
    contexts=(Context("target_x", "m", 0.469846, 0.866025, limits=(-20.0, 20.0)), Context("target_y", "m", -0.171010, 0.5, limits=(-20.0, 20.0))),
    #: Effective-friction factor of the analytic model, fitted to the engine before any audit.
    model_fields={"mu_scale": (float, Field(FITTED_MU_SCALE, gt=0.1, le=10))},
    simulators={"mujoco": "probecommit.tasks.push2d.sim_mujoco:MujocoPush2DSimulator",
                "pybullet": "probecommit.tasks.push2d.sim_pybullet:PybulletPush2DSimulator"},
    analytic=False,
    summary={"probe": "pulse / 2-D rest", "action": "2-D impulse",
             "sigma": "5 cm", "budgets": "0, 2, 5", "metric": "miss (m)", "n": "18 x 6"},
    doc="A box on a plane struck by a 2-D impulse to stop at a 2-D target.",
)
SPEC = family(DECLARATION, Push2DModel)
