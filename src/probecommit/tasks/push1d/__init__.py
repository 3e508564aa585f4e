"""1-D push (paper Table II, analytic): a box pushed to stop at a target distance.

Registers ``push1d``. Every choice (the paper gives the latents, probe/action kind,
sigma, budgets and instance count, nothing else):

* **Latents and prior** ``(mu, m, k_d)``: Coulomb friction ``U[0.2, 0.6]``, mass
  ``U[0.5, 1.5]`` kg, linear damping ``U[0.5, 3.0]`` N s/m (damping time constants
  0.17-3 s, so damping and friction both matter at these speeds). Jitter
  ``(0.01, 0.025, 0.06)``, about 2.5% of each width.
* **Dynamics**: ``m dv/dt = -mu m g - k_d v`` from ``v0 = J / m``; closed-form stop
  distance in :mod:`probecommit.tasks.push1d.model`.
* **Probe**: a known pulse from ``{1, 2, 3}`` N s (uniform random with replacement),
  reading the slide distance with ``sigma = 5`` cm (model and simulator). The box is
  returned to its start pose after each probe.
* **Action**: an impulse on a geometric grid, ``0.25 * 1.01^i`` N s up to 10 N s (371).
* **Context**: the target distance; **loss**: miss ``|d(J) - target|`` in metres,
  divided by the margin ``gamma`` (``with_margin``).
* **Instances** (``configs/paper/push1d.yaml``): the 3x3x3 grid of truths at 1/8, 1/2
  and 7/8 of each prior width (``mu in {0.25, 0.4, 0.55}``, ``m in {0.625, 1.0,
  1.375}``, ``k_d in {0.8125, 1.75, 2.6875}``) crossed with targets ``{0.5, 1.0,
  1.5}`` m: 81 instances x 6 seeds; budgets 0, 2, 5.
* **Decision coordinate**: ``mu`` (latent 0), domain width 0.4.
* **Simulator**: the closed form at the truth plus noise (the paper: no scene).
"""

from __future__ import annotations

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.push1d.model import PRIOR_HIGH, PRIOR_LOW, Push1DModel

DECLARATION = Declaration(
    name="push1d",
    latents=(Latent("mu", "", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("m", "kg", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True),
             Latent("k_d", "N s/m", PRIOR_LOW[2], PRIOR_HIGH[2], positive=True)),
    probe_grid=Push1DModel.probe_grid, action_grid=Push1DModel.action_grid,
    loss="continuous", sigma=0.05, sigma_limit=10, decision="mu",
    contexts=(Context("target", "m", 0.5, 1.0, limits=(0.0, 20.0)),),
    simulators={"analytic": "probecommit.tasks.push1d.sim_analytic:AnalyticPush1DSimulator"}, analytic=False,
    summary={"probe": "pulse / slide distance", "action": "impulse",
             "sigma": "5 cm", "budgets": "0, 2, 5", "metric": "miss (m)", "n": "81 x 6"},
    doc="A box pushed along a line by an impulse to stop at a target distance.",
)
SPEC = family(DECLARATION, Push1DModel)
