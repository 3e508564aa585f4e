"""The rig model: insertion at rig scale, read by a touch switch (paper Sec. V-D).

The physical-arm run inserted a 5.9 mm tool into a pocket machined in a rigid block,
the simulation's geometry at ``RIG_SCALE = 3.86``: every length of the insertion model
(half-gap, capture window, prior, tap and aim grids) is multiplied by it, which keeps
the prior-to-window ratio of the simulation (10 / 1.7 = 38.6 / 6.56 = 5.9) exactly.

A tap descends in 0.5 mm steps until a touch switch on the tool closes: on the block
top (reading 0 mm) or, once the tool has gone ``ALLOWANCE_MM`` below the top without
touching, through the opening (reading ``-ALLOWANCE_MM``). The tool's flat end fits
the opening when its centre is within ``hg(c) - r`` of the pocket centre, so the
deployed boundary offset is ``-TOOL_RADIUS_MM`` (the rig's counterpart of the
simulation's ``-r``); a boundary fault pulls it inward by ``f`` mm
(``boundary_offset = -r - f``). Realized failure is the aim outside the model's window
of the measured centre, ``|a - x_hole| >= w_rig(c) = 3.86 (0.6 c + 1.1)`` mm
(6.56 mm at c = 1; the paper's 6.57 mm); whether the tool physically entered is
recorded beside it, as the paper's Table IX does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probecommit.tasks.insertion.model import InsertionModel

#: Rig geometry over simulation geometry (paper: 3.86x).
RIG_SCALE = 3.86
#: The tool's diameter (mm) and the deployed boundary offset it implies.
TOOL_DIAMETER_MM = 5.9
TOOL_RADIUS_MM = TOOL_DIAMETER_MM / 2
#: Descent step of the touch-switch tap (mm).
DESCENT_STEP_MM = 0.5
#: A tap that descends this far below the block top without the switch closing went
#: through the opening. Chosen as a few descent steps more than any edge contact of a
#: flat-ended tool can reach, and well above the pocket floor.
ALLOWANCE_MM = 10.0
#: The pocket's depth (mm): the simulation's 15 mm at rig scale.
POCKET_DEPTH_MM = 15.0 * RIG_SCALE
#: Readings a touch-switch tap can physically give (mm): the start height down to the allowance.
READING_RANGE_MM = (-ALLOWANCE_MM - 2.0, 2.0)
#: Prior box on (x_hole [mm], c): the simulation's at rig scale.
PRIOR_LOW = (-10.0 * RIG_SCALE, 0.7)
PRIOR_HIGH = (10.0 * RIG_SCALE, 1.3)


def rig_half_gap(c: np.ndarray) -> np.ndarray:
    """The pocket's half-opening ``3.86 (4 + 0.6 c)`` mm."""
    return RIG_SCALE * (4.0 + 0.6 * np.asarray(c))


def rig_window(c: np.ndarray) -> np.ndarray:
    """The model's capture half-width ``3.86 (0.6 c + 1.1)`` mm."""
    return RIG_SCALE * (0.6 * np.asarray(c) + 1.1)


@dataclass(frozen=True)
class RigModel(InsertionModel):
    """Insertion at rig scale with a touch-switch tap (see the module docstring).

    Args:
        boundary_offset: Offset added to ``hg(c)`` for the through-the-opening boundary
            (mm); ``-TOOL_RADIUS_MM`` as deployed, more negative under a boundary fault.
        variant: Label stored with every episode this model scores.
        sigma: Observation noise the likelihood assumes (mm): the descent step.
        margin: ``gamma``, the capture window shrink used when scoring aims.
        prior_low, prior_high: Box prior on ``(x_hole, c)``.
    """

    boundary_offset: float = -TOOL_RADIUS_MM
    variant: str = "deployed"
    sigma: float = DESCENT_STEP_MM
    margin: float = 1.0
    prior_low: np.ndarray = field(default_factory=lambda: np.array(PRIOR_LOW))
    prior_high: np.ndarray = field(default_factory=lambda: np.array(PRIOR_HIGH))
    jitter_scale: np.ndarray = field(default_factory=lambda: np.array([0.6 * RIG_SCALE, 0.006]))

    # name, latent_names and context_names: from the declaration (probecommit.tasks.rig).
    #: Nine taps, the simulation's -12..12 mm in 3 mm steps at rig scale ``[9, 1]``.
    probe_grid = np.round(RIG_SCALE * InsertionModel.probe_grid, 10)
    #: 41 aims, the simulation's 0.5 mm grid over [-10, 10] mm at rig scale ``[41, 1]``.
    action_grid = np.round(RIG_SCALE * InsertionModel.action_grid, 10)
    decision_domain_width = 20.0 * RIG_SCALE
    observation_range = READING_RANGE_MM

    def reads_pocket(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Whether a tap at ``u[E]`` goes through the opening for each particle ``[E, N]``."""
        theta = np.asarray(theta)
        u = np.asarray(u, dtype=float).reshape(theta.shape[0], 1)
        return np.abs(u - theta[..., 0]) < rig_half_gap(theta[..., 1]) + self.boundary_offset

    #: The switch reads the allowance through the opening, the plate top elsewhere (``predict``
    #: is insertion's: the level of whether ``reads_pocket``).
    reading_levels = (-ALLOWANCE_MM, 0.0)

    def success_interval_parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Open interval of aims inside the model's window, ``x -+ gamma w_rig(c)``, as ``(x, w_rig(c))``."""
        theta = np.asarray(theta)
        return theta[..., 0], rig_window(theta[..., 1])
