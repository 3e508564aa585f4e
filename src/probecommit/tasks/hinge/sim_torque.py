"""The hinge's scenes with the commit read as a torque (docs/decisions.md, "ex27"; model in ``hinge.torque``).

Why: the ex27 experiment commits a torque while the probe stays the frozen coast, so each scene keeps its ``coast``
query and adds a ``push`` query that commits run (``commit_query``). MuJoCo applies the torque on the hinge as
``qfrc_applied`` for ``round(push_s / 1 ms)`` steps from rest, then lets the frozen coast run to a stop; an impulse
(``push_s = 0``) is the joint speed ``J / M`` at rest (``M``: MuJoCo's own joint inertia). Built by the experiment
itself (not registered as engines), one simulator per unit.
"""

from __future__ import annotations

from probecommit.tasks.hinge.sim_analytic import AnalyticHingeSimulator
from probecommit.tasks.hinge.sim_mujoco import TIMESTEP_S, MujocoHingeSimulator
from probecommit.tasks.hinge.torque import torque_angle


class AnalyticHingeTorqueSimulator(AnalyticHingeSimulator):
    """Closed-form coast probes and closed-form torque commits (quick runs and tests)."""

    commit_query = "push"

    def __init__(self, push_s: float, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)
        self.push_s = float(push_s)

    def push(self, f: float, b: float, m: float, torque: float) -> float:
        """Named query: stop angle (rad) after the torque (impulse) from rest."""
        return float(torque_angle(torque, f, b, m, self.push_s))


class MujocoHingeTorqueSimulator(MujocoHingeSimulator):
    """MuJoCo's frozen door: coast probes as frozen, torque commits pushed by the hinge motor."""

    commit_query = "push"
    not_finite = "mujoco door did not stop after a torque of {action}"

    def __init__(self, push_s: float, noise_sigma: float = 0.02) -> None:
        super().__init__(noise_sigma)
        self.push_s = float(push_s)

    def push(self, f: float, b: float, m: float, torque: float) -> float:
        """Named query: the angle (rad) where the door stops after the torque (impulse) from rest."""
        mj = self._mj
        model, data = self._instance(f, b, m)
        mj.mj_resetData(model, data)
        if self.push_s <= 0:
            mj.mj_forward(model, data)
            data.qvel[0] = torque / data.M[0]
            return self.settle(model, data)
        data.qfrc_applied[0] = torque
        for _ in range(int(round(self.push_s / TIMESTEP_S))):
            mj.mj_step(model, data)
        data.qfrc_applied[0] = 0.0
        return self.settle(model, data)
