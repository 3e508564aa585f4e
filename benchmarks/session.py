"""Robot session latency: Session.decide() and Session.observe() at 2048 particles (the rig's belief).

A decision must come back well under 10 ms (issue 12). This prints the median, 99th
percentile and maximum of each call over many episodes of the frozen rig protocol on
the analytic rig, fsync included for observe (every call appends a record before it
returns), and the decide time as a fraction of the 10 ms target.

    python benchmarks/session.py [--episodes 200]
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

import probecommit
from probecommit.runner.config import config_data, load_config, parse_config
from probecommit.tasks.rig.sim_base import AnalyticRigSimulator


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200)
    args = parser.parse_args()
    data = config_data(load_config(probecommit.paper_config("rig")))
    data["simulator"]["engine"] = "analytic"
    config = parse_config(data)
    sim = AnalyticRigSimulator(misread_rate=0.01)
    rng = np.random.default_rng(0)
    decide_s, observe_s = [], []
    with tempfile.TemporaryDirectory() as tmp, probecommit.Session.open(tmp, config) as session:
        for e in range(args.episodes):
            theta = np.array([rng.uniform(-38.6, 38.6), rng.uniform(0.7, 1.3)])
            session.start_episode(f"p{e % 12}", taps=1 + e % 5)
            while (u := session.next_probe()) is not None:
                y = float(sim.probe(theta, np.array([u]), rng)[0])
                t0 = time.perf_counter()
                session.observe(u, y)
                observe_s.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            session.decide()
            decide_s.append(time.perf_counter() - t0)
            session.record_outcome(entered=True)
    for name, values in (("decide", decide_s), ("observe (fsync incl.)", observe_s)):
        ms = np.array(values) * 1e3
        print(f"{name:22s} n={len(ms):4d}  median {np.median(ms):6.3f} ms  p99 {np.percentile(ms, 99):6.3f} ms  "
              f"max {ms.max():6.3f} ms")
    print(f"decide median / 10 ms target: {np.median(decide_s) * 1e3 / 10:.3f} "
          f"({10 / (np.median(decide_s) * 1e3):.0f}x under)")


if __name__ == "__main__":
    main()
