"""Darts (paper Table II, MuJoCo): a dart thrown with linear drag to land at a target.

Registers ``darts``. Every choice (the paper gives latents, probe/action kind, sigma,
budgets and the 6 x 3 instance set size, nothing else):

* **Latents and prior** ``(k_d, m, g)``: drag ``U[0.004, 0.02]`` N s/m, mass
  ``U[0.02, 0.05]`` kg, gravity ``U[8.8, 10.8]`` m/s^2; the drag rate ``b = k_d / m``
  spans 0.08-1.0 1/s. Jitter ``(0.000625, 0.00075, 0.05)``, about 2.5% of each width.
  Only ``b`` and ``g`` are identifiable (linear drag).
* **Scene** (:mod:`probecommit.tasks.darts.sim_mujoco`): a 1 cm sphere of mass ``m`` on
  x/z slide joints with joint damping ``k_d`` (linear drag), gravity ``-g`` per truth,
  RK4 at 1 ms, released at 1.0 m height; landing where the centre crosses ``z = 0``,
  interpolated linearly between steps.
* **Analytic model**: the closed form for linear drag, landing time by Newton's method
  (6 steps; converged to 1e-13 m on the prior). No fitted parameter: the engine agrees
  with it to 1.3 micrometres on 120 test launches.
* **Probe**: a known throw ``(v, alpha)`` from ``{(4 m/s, 10 deg), (5, 30), (6, 50)}``,
  reading the landing distance with ``sigma = 2`` cm (model and simulator); each probe
  is an independent launch.
* **Action**: a launch ``(v, alpha)``: elevations ``{10, 30, 50}`` deg, speeds in 0.01 m/s
  steps over per-elevation ranges reaching 2-4 m under every prior truth (1483);
  **context**: the target distance; **loss**: ``|x_land - target|`` (m) / ``gamma``.
* **Instances** (``configs/paper/darts.yaml``): 6 truths (a Latin hypercube at stratum
  centres with fixed permutations) x targets ``{2, 3, 4}`` m; 8 seeds; budgets 0, 2, 5.
* **Decision coordinate**: the drag rate ``b = k_d / m``; domain width
  ``0.02/0.02 - 0.004/0.05 = 0.92`` 1/s.
"""

from __future__ import annotations

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.darts.model import PRIOR_HIGH, PRIOR_LOW, DartsModel

DECLARATION = Declaration(
    name="darts",
    latents=(Latent("k_d", "N s/m", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("m", "kg", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True),
             Latent("g", "m/s^2", PRIOR_LOW[2], PRIOR_HIGH[2], positive=True)),
    probe_grid=DartsModel.probe_grid, action_grid=DartsModel.action_grid,
    #: No latent is the decision coordinate: the model's decision() is the drag rate k_d / m.
    loss="continuous", sigma=0.02, sigma_limit=10, decision=None,
    contexts=(Context("target", "m", 2.0, 3.0, limits=(0.0, 100.0)),),
    simulators={"mujoco": "probecommit.tasks.darts.sim_mujoco:MujocoDartsSimulator"},
    analytic=False,
    summary={"probe": "throw / landing point", "action": "launch (v, alpha)",
             "sigma": "2 cm", "budgets": "0, 2, 5", "metric": "miss (m)", "n": "18 x 8"},
    doc="A dart thrown with linear drag to land at a target distance.",
)
SPEC = family(DECLARATION, DartsModel)
