"""Check (issue 42, target 6): no abort at exit in 50 consecutive replays at E = 12,288.

A replay once ended in SIGABRT at interpreter exit ("terminate called without an active
exception": a native thread still running when the process tore down). This makes one
insertion run of ``--instances`` x 4 episodes (3072 x 4 = 12,288 by default; k = 1..8,
N = 1024) and replays it ``--times`` times in a row, each ``probecommit replay`` a process
of its own into a fresh directory, and counts the replays that did not exit 0: an abort
(signal 6 / exit 134, or the C++ runtime's message on stderr) or any other failure.

    python benchmarks/replay_aborts.py                          # the target: 50 replays at E = 12288 (long)
    python benchmarks/replay_aborts.py --instances 96 --times 3 # a brief check

Prints each failure's exit status and the last line of its stderr, the load average, and
the count against the target (0 of 50).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CONFIG = """name: aborts
task: insertion
seed: 2026
repeats: 4
instances: {{split: aborts, count: {instances}, seed: 103}}
probes: {{schedule: random, budget: 8}}
belief: {{particles: 1024, nu: 0.8}}
simulator: {{engine: {engine}}}
methods: [probe_robust]
"""

ABORT_MESSAGE = "terminate called"


def cli(*args: str) -> subprocess.CompletedProcess:
    """``probecommit ARGS`` as a process of its own, from this tree."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "COLUMNS": "120"}
    return subprocess.run([sys.executable, "-m", "probecommit", *args], env=env, capture_output=True, text=True)


def aborted(done: subprocess.CompletedProcess) -> bool:
    """An abort at exit: SIGABRT (``-6`` from ``subprocess``, 134 from a shell) or the C++ runtime's message."""
    return done.returncode in (-6, 134) or ABORT_MESSAGE in done.stderr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=3072, help="Instances (x 4 repeats = E).")
    ap.add_argument("--times", type=int, default=50, help="Consecutive replays.")
    ap.add_argument("--engine", default="analytic", help="The run's engine (analytic or mujoco).")
    args = ap.parse_args()
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        (tmp / "c.yaml").write_text(CONFIG.format(instances=args.instances, engine=args.engine))
        made = cli("run", str(tmp / "c.yaml"), "--out", str(tmp / "run"))
        if made.returncode != 0:
            raise SystemExit(f"the run failed (exit {made.returncode}): {made.stderr.strip().splitlines()[-1:]}")
        aborts, failures, start = 0, 0, time.perf_counter()
        for i in range(args.times):
            out = tmp / "replay"
            shutil.rmtree(out, ignore_errors=True)
            done = cli("replay", str(tmp / "run"), "--out", str(out))
            if done.returncode != 0 or aborted(done):
                kind = "ABORT" if aborted(done) else "failure"
                aborts += kind == "ABORT"
                failures += kind != "ABORT"
                last = (done.stderr.strip().splitlines() or [""])[-1]
                print(f"  replay {i + 1}: {kind}, exit {done.returncode}: {last[:160]}")
            load.append(os.getloadavg()[0])
    episodes = 4 * args.instances
    print(f"{args.times} consecutive replays of a {args.engine} insertion run, E = {episodes} "
          f"({time.perf_counter() - start:.0f} s; load average {min(load):.1f}-{max(load):.1f} on {os.cpu_count()} CPUs)")
    print(f"  aborts at exit: {aborts} of {args.times}; other failures: {failures}")
    met = aborts == 0 and failures == 0
    print(f"  target (issue 42): no abort in 50 consecutive replays at E = 12288: "
          f"{'met' if met and args.times >= 50 and episodes >= 12288 else 'met for this shorter check' if met else 'MISSED'}")


if __name__ == "__main__":
    main()
