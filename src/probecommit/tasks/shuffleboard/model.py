"""Shuffleboard model: a puck struck along a board, the 1-D push's physics at shuffleboard scale.

theta = (mu, m, k_d): puck-board Coulomb friction, puck mass (kg) and linear damping
(N s/m). A strike of impulse ``J`` gives ``v0 = J / m`` and the puck slides under
``m dv/dt = -mu m g - k_d v`` until it stops: exactly the 1-D push's dynamics and closed
form (:class:`probecommit.tasks.push1d.model.Push1DModel`, whose ``predict`` and ``loss``
this model inherits); only the scale differs: a waxed board (low friction), a 0.2-0.6 kg
puck, targets 1.5-3.5 m, strikes up to 4 N s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.push1d.model import Push1DModel

#: Prior box on (mu, m [kg], k_d [N s/m]).
PRIOR_LOW = (0.1, 0.2, 0.05)
PRIOR_HIGH = (0.3, 0.6, 0.3)
#: Known probe strikes (N s).
PROBE_STRIKES = (0.5, 1.0, 1.5)
#: Commit strikes (N s): 0.1 N s times 1.01^i up to 4 N s (371); a half step moves a slide
#: by at most about 1 %.
ACTION_STRIKES = np.round(0.1 * 1.01 ** np.arange(0, int(np.log(40.0) / np.log(1.01)) + 1), 10)


@dataclass(frozen=True)
class ShuffleboardModel(Push1DModel):
    """The shuffleboard task model (the 1-D push model with its own prior and grids).

    Args:
        sigma: Observation noise the likelihood assumes (m).
        margin: ``gamma``; the modeled miss is divided by it (1 = none).
        prior_low, prior_high: Box prior on ``(mu, m, k_d)``.
        variant: Label stored with every episode this model scores.
    """

    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    #: About 2.5 % of each prior width.
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.005, 0.01, 0.00625]))

    # name, latent_names and context_names: from the declaration (probecommit.tasks.shuffleboard).
    probe_grid = np.array(PROBE_STRIKES)[:, None]
    action_grid = ACTION_STRIKES[:, None]
    decision_domain_width = PRIOR_HIGH[0] - PRIOR_LOW[0]
    #: Slides a strike can physically read (m): noise below zero up to the board's far end.
    observation_range = (-1.0, 110.0)
