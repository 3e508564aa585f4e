"""A robot loop on a continuous-loss family with a target: push a box to stop at a distance.

The same Session as ``robot_loop.py`` (insertion), for the ``push1d`` family: each episode
says its target (the context), the robot pushes the box with the scheduled probe pulses and
reports how far it slid, the session commits an impulse, and after the run the box's
friction, mass and damping (measured on a test stand) are recorded as the truth. Run:

    python examples/push_robot_loop.py runs/my-push-session

then ``probecommit audit runs/my-push-session`` (coverage, support escape and optimism of
the miss) and ``probecommit replay runs/my-push-session``. It resumes where the log stopped.
"""

from __future__ import annotations

import sys

import numpy as np

import probecommit
from probecommit.tasks.push1d.model import stop_distance

CONFIG = {"name": "push-loop", "task": "push1d", "seed": 7, "repeats": 1, "instances": {"contexts": [[1.0]]},
          "probes": {"schedule": "random", "budget": 3}, "belief": {"particles": 1024}}


class StandInPusher:
    """A simulated push stand standing in for the robot (closed-form slide, 5 cm reading noise)."""

    def __init__(self, mu: float, m: float, k_d: float, seed: int) -> None:
        self.theta = (mu, m, k_d)
        self.rng = np.random.default_rng(seed)

    def push_and_measure(self, pulse: float) -> float:
        return float(stop_distance(pulse, *self.theta)) + 0.05 * float(self.rng.standard_normal())

    def commit(self, impulse: float) -> float:
        return float(stop_distance(impulse, *self.theta))


def main(log_dir: str) -> None:
    boxes = {"felt": (0.45, 1.2, 1.0), "wood": (0.3, 0.8, 2.0)}
    with probecommit.Session.open(log_dir, CONFIG) as session:
        done = {(ep.position, ep.taps) for ep in session.episodes.values() if ep.done}
        for name, theta in boxes.items():
            pusher = StandInPusher(*theta, seed=len(session.episodes))
            for pushes in (0, 1, 3):
                if (name, pushes) in done:
                    continue
                if session.current is None:
                    session.start_episode(name, taps=pushes, context=[1.0])  # target: stop 1 m away
                while (u := session.next_probe()) is not None:
                    session.observe(u, pusher.push_and_measure(u))
                decision = session.decide()
                slid = pusher.commit(decision.action)
                print(f"{name}: {pushes} probe push(es) -> impulse {decision.action:.2f} N s, slid {slid:.2f} m "
                      f"(predicted worst miss {decision.score:.2f} m)")
                session.record_outcome(slid=slid)
            session.record_truth(name, list(theta))  # the test stand's measurement
    print(f"log: {session.path}\nnext: probecommit audit {log_dir}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "runs/push-loop")
