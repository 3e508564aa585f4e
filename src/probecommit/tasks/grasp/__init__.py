"""Grasp (paper Table II): squeeze to learn the hold force, then lift a delicate object.

Registers ``grasp``. Every choice (the paper gives the latents, the probe/action kind,
sigma, budgets, 16 x 80 and "a force-balance model with a MuJoCo lift check", nothing else):

* **Latents and prior** ``(mu, m)``: pad-object friction ``U[0.2, 1.0]``, object mass
  ``U[0.05, 0.5]`` kg.
* **Model** (:mod:`probecommit.tasks.grasp.model`): the force balance
  ``2 mu F >= m (g + a)`` with a 2 m/s^2 lift; success when the grip holds and stays
  below 1.5x the force that holds (a delicate object; without an upper limit the
  robust grip is always the strongest and probing cannot matter).
* **Probe**: a squeeze, relaxing to a known force in ``{0.25, 0.5, 1, 2, 4}`` N for 50 ms
  and reading the slip (mm, ``sigma = 2`` mm).
* **Action**: the grip force per pad on ``0.2 * 1.02^i`` N up to 5 N (163), a small servo
  gripper's range.
* **Truth**: the MuJoCo lift check (:mod:`probecommit.tasks.grasp.sim_mujoco`) for holding;
  the crush limit is a rule on the truth's force balance (no engine models fracture).
* **Instances** (``configs/paper/grasp.yaml``): the 4 x 4 grid of stratum centres, 80
  seeds, budgets 0, 2, 5, 8. A truth is *feasible* when some grid grip succeeds in the
  simulator; success is reported on the feasible subset (paper Table V).
* **Decision coordinate**: the hold force of the lift ``F_lift = m (g + a) / (2 mu)``.
"""

from __future__ import annotations

from probecommit.tasks.declare import Declaration, Latent, family
from probecommit.tasks.grasp.model import PRIOR_HIGH, PRIOR_LOW, GraspModel

DECLARATION = Declaration(
    name="grasp",
    latents=(Latent("mu", "", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("m", "kg", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True)),
    probe_grid=GraspModel.probe_grid, action_grid=GraspModel.action_grid,
    #: No latent is the decision coordinate: the model's decision() is the hold force m (g + a) / (2 mu).
    loss="binary", sigma=2.0, sigma_limit=100, decision=None,
    simulators={"mujoco": "probecommit.tasks.grasp.sim_mujoco:MujocoGraspSimulator",
                "analytic": "probecommit.tasks.grasp.sim_base:AnalyticGraspSimulator"},
    analytic=False,
    summary={"probe": "squeeze / slip", "action": "grip force",
             "sigma": "2 mm", "budgets": "0, 2, 5, 8", "metric": "success (feasible)", "n": "16 x 80"},
    doc="A delicate object gripped hard enough to lift, gently enough not to crush.",
)
SPEC = family(DECLARATION, GraspModel)
