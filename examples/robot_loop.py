"""Drive probecommit from your own robot code: the loop of paper Sec. V-D with a stand-in robot.

Replace ``StandInRobot`` with your arm's driver: ``tap(u)`` moves the tool over lateral
position ``u`` (mm, in the block's frame), descends in 0.5 mm steps until the touch switch
closes or the allowance is passed, and returns the height where it stopped (0 on the
block, -10 through the opening); ``insert(a)`` commits the tool at ``a`` and says whether
it entered. Run:

    python examples/robot_loop.py runs/my-rig-session

then ``probecommit audit runs/my-rig-session`` (Table IX) and
``probecommit replay runs/my-rig-session --fault boundary`` (Fig. 7c). Kill it at any
point and run it again: it resumes where the log stopped.
"""

from __future__ import annotations

import sys

import numpy as np

import probecommit
from probecommit.runner.config import load_config
from probecommit.tasks.rig.sim_base import AnalyticRigSimulator


class StandInRobot:
    """A simulated rig standing in for the arm (closed-form geometry, 1 % misreads)."""

    def __init__(self, x_hole: float, c: float, seed: int) -> None:
        self.theta = np.array([x_hole, c])
        self.sim = AnalyticRigSimulator(misread_rate=0.01)
        self.rng = np.random.default_rng(seed)

    def tap(self, u: float) -> float:
        return float(self.sim.probe(self.theta, np.array([u]), self.rng)[0])

    def insert(self, a: float) -> bool:
        return bool(self.sim.execute(self.theta, np.array([a]))["entered"])


def main(log_dir: str) -> None:
    config = load_config(probecommit.paper_config("rig"))
    positions = {"left": (-21.0, 0.9), "centre": (2.5, 1.1), "right": (27.0, 1.0)}
    with probecommit.Session.open(log_dir, config) as session:
        done = {(ep.position, ep.taps) for ep in session.episodes.values() if ep.done}
        for name, (x_hole, c) in positions.items():  # the block, slid by hand to each position
            robot = StandInRobot(x_hole, c, seed=len(session.episodes))
            for taps in (1, 3, 5):
                if (name, taps) in done:
                    continue
                if session.current is None:
                    session.start_episode(name, taps=taps)
                while (u := session.next_probe()) is not None:
                    session.observe(u, robot.tap(u))
                decision = session.decide()
                print(f"{name}: {taps} tap(s) -> aim {decision.action:+.2f} mm, predicted failure "
                      f"{decision.score:.2f}, retained [{decision.retained[0]:+.1f}, {decision.retained[1]:+.1f}] mm "
                      f"({decision.seconds * 1e3:.1f} ms)")
                session.record_outcome(entered=robot.insert(decision.action))
            # After the run, a touch sweep brackets the opening: that is the truth the audit needs.
            session.record_truth(name, [x_hole, c])
    print(f"log: {session.path}\nnext: probecommit audit {log_dir}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "runs/robot-loop")
