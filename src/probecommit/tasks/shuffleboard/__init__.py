"""Shuffleboard (paper Table II, SAPIEN/PhysX): a puck struck to stop at a target.

Registers ``shuffleboard``. Every choice (the paper gives the latents, probe/action kind,
sigma 5 cm, budgets 0, 2, 5, 512 particles and 18 x 6, nothing else):

* **Latents and prior** ``(mu, m, k_d)``: puck-board friction ``U[0.1, 0.3]`` (a waxed
  board), puck mass ``U[0.2, 0.6]`` kg, linear damping ``U[0.05, 0.3]`` N s/m. Jitter about
  2.5 % of each width.
* **Dynamics and model**: the 1-D push's (``m dv/dt = -mu m g - k_d v``) and its closed
  form, reused (:mod:`probecommit.tasks.shuffleboard.model`).
* **Probe**: a strike of known impulse from ``{0.5, 1.0, 1.5}`` N s, reading the slide
  with ``sigma = 5`` cm (model and simulator); the puck is returned after each probe.
* **Action**: a strike on ``0.1 * 1.01^i`` N s up to 4 N s (371); **context**: the target
  distance; **loss**: the miss in metres (Table V reports its mean and P90).
* **Instances** (``configs/paper/shuffleboard.yaml``): 6 truths (a Latin hypercube at
  stratum centres) x targets ``{1.5, 2.5, 3.5}`` m; 6 seeds; 512 particles; budgets 0, 2, 5.
* **Scene** (:mod:`probecommit.tasks.shuffleboard.sim_sapien`): PhysX on the CPU, a box puck
  on a static board, PhysX linear damping ``k_d / m``; no parameter fitted (it matches
  the closed form within 0.6 %).
* **Decision coordinate**: ``mu`` (latent 0), domain width 0.2.
"""

from __future__ import annotations

from probecommit.tasks.declare import Context, Declaration, Latent, family
from probecommit.tasks.shuffleboard.model import PRIOR_HIGH, PRIOR_LOW, ShuffleboardModel

DECLARATION = Declaration(
    name="shuffleboard",
    latents=(Latent("mu", "", PRIOR_LOW[0], PRIOR_HIGH[0], positive=True),
             Latent("m", "kg", PRIOR_LOW[1], PRIOR_HIGH[1], positive=True),
             Latent("k_d", "N s/m", PRIOR_LOW[2], PRIOR_HIGH[2], positive=True)),
    probe_grid=ShuffleboardModel.probe_grid, action_grid=ShuffleboardModel.action_grid,
    loss="continuous", sigma=0.05, sigma_limit=10, decision="mu",
    contexts=(Context("target", "m", 1.5, 2.5, limits=(0.0, 50.0)),),
    simulators={"sapien": "probecommit.tasks.shuffleboard.sim_sapien:SapienShuffleboardSimulator",
                "analytic": "probecommit.tasks.push1d.sim_analytic:AnalyticPush1DSimulator"},
    analytic=False,
    summary={"probe": "strike / slide", "action": "strike",
             "sigma": "5 cm", "budgets": "0, 2, 5", "metric": "miss (m), mean / P90", "n": "18 x 6"},
    doc="A puck struck along a board to stop at a target distance.",
)
SPEC = family(DECLARATION, ShuffleboardModel)
