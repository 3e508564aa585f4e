"""Hinge (paper Table II, MuJoCo): a door released to coast to a target angle.

Registers ``hinge``. Every choice (the paper gives the latents, probe/action kind, sigma,
budgets and the 6 x 3 instance set with 16 seeds, nothing else):

* **Latents and prior** ``(f, b, m)``: hinge Coulomb friction torque ``U[0.2, 0.8]`` N m,
  viscous damping ``U[0.1, 0.5]`` N m s/rad, door mass ``U[2, 6]`` kg (a 0.5 m wide
  cabinet-size panel, ``I = m W^2 / 3`` = 0.17-0.5 kg m^2); damping time constants
  ``I / b`` of 0.3-5 s, so friction and damping both shape a coast. Jitter about 2.5 %
  of each width.
* **Dynamics**: ``I dw/dt = -f - b w``; closed-form stop angle in
  :mod:`probecommit.tasks.hinge.model` (the 1-D push's closed form, reused).
* **Probe**: a coast released at a known speed from ``{0.5, 1.0, 1.5}`` rad/s (stop angles
  0.02-0.9 rad over the prior), reading the stop angle with ``sigma = 0.02`` rad (model
  and simulator); the door is returned after each probe.
* **Action**: the release speed the hinge motor's torque brings the door to, on a
  geometric grid ``0.2 * 1.01^i`` rad/s up to 8 rad/s (371); **context**: the target
  angle; **loss**: ``|stop angle - target|`` (rad) divided by the margin.
* **Instances** (``configs/paper/hinge.yaml``): 6 truths (a Latin hypercube at stratum
  centres, the darts permutations) x targets ``{0.5, 1.0, 1.5}`` rad; 16 seeds; budgets 0, 2, 5.
* **Scene** (:mod:`probecommit.tasks.hinge.sim_mujoco`): a door panel on a hinge joint with
  ``frictionloss = f`` and ``damping = b``; it matches the closed form to 1.4 mrad on 25
  coasts over the prior's corners (the reading noise is 20 mrad), so no parameter is fitted.
* **Decision coordinate**: the friction torque ``f`` (latent 0), domain width 0.6 N m.
"""

from __future__ import annotations

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.hinge.model import PRIOR_HIGH, PRIOR_LOW, HingeModel

DECLARATION = Declaration(
    name="hinge",
    latents=(Latent("f", "N m", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("b", "N m s/rad", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True),
             Latent("m", "kg", PRIOR_LOW[2], PRIOR_HIGH[2], positive=True)),
    probe_grid=HingeModel.probe_grid, action_grid=HingeModel.action_grid,
    loss="continuous", sigma=0.02, sigma_limit=10, decision="f",
    contexts=(Context("target", "rad", 0.5, 1.0, limits=(0.0, 6.2832)),),
    simulators={"mujoco": "probecommit.tasks.hinge.sim_mujoco:MujocoHingeSimulator",
                "analytic": "probecommit.tasks.hinge.sim_analytic:AnalyticHingeSimulator"},
    analytic=False,
    summary={"probe": "coast / stop angle", "action": "release speed (torque)",
             "sigma": "0.02 rad", "budgets": "0, 2, 5", "metric": "miss (rad)", "n": "18 x 16"},
    doc="A door on a hinge released to coast to a target angle.",
)
SPEC = family(DECLARATION, HingeModel)
