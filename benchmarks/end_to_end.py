"""End to end as the user runs it (issue 42, target 1): `probecommit run` as a process against a
plain per-episode NumPy loop.

The study: analytic insertion, 480 instances x 4 repeats, random taps, k = 1..8, N = 1024,
Probe-Robust only, in units of 4 instances (the default: 120 units, each stored durably). The
command is timed as a process from start to exit (interpreter start-up, imports, rollouts,
beliefs, commits, every durable write and the merge included), into a fresh run directory
each time. The plain loop (``benchmarks/belief.py``'s ``run_plain``, written independently of
the package) filters the same number of episodes with the same number of taps and commits at
every budget; it runs in a process of its own too, but only its loop is timed (its start-up
and data are not counted: a conservative anchor). ``run`` is timed as shipped (units in
threads, one per CPU up to 4) and with ``--threads 1``. The arms take turns for ``--rounds``
rounds after a warm-up; medians, ratios of the medians and the range of per-round ratios are
printed, with the load average.

    python benchmarks/end_to_end.py [--instances 480] [--repeats 4] [--rounds 3] [--unit-instances 4]

Target: plain / run >= 3 (the run at least three times as fast) on an idle 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent

CONFIG = """name: e2e
seed: 7
repeats: {repeats}
instances: {{split: e2e, count: {instances}, seed: 1}}
probes: {{schedule: random, budget: 8}}
belief: {{particles: 1024}}
simulator: {{engine: analytic}}
methods: [probe_robust]
unit_instances: {unit_instances}
"""

PLAIN = """
import json, sys, time
import numpy as np
np.seterr(all="ignore")
sys.path.insert(0, {here!r})
from belief import make_data, run_plain
episodes = {episodes}
model, u, y = make_data(episodes, 8)
t0 = time.perf_counter()
run_plain(model, u, y, list(range(episodes)), 1024)
print(json.dumps({{"seconds": time.perf_counter() - t0}}))
"""


def run_command(config: Path, out: Path, threads: int | None) -> float:
    """Wall seconds of ``probecommit run`` as a process, into a fresh ``out``."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-m", "probecommit", "run", str(config), "--out", str(out)]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "COLUMNS": "120"}
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True)
    return time.perf_counter() - t0


def plain_loop(episodes: int) -> float:
    """Seconds of the plain loop alone, in a process of its own."""
    code = PLAIN.format(here=str(HERE), episodes=episodes)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])["seconds"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=480)
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--unit-instances", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    episodes = args.instances * args.repeats
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        config = tmp / "e2e.yaml"
        config.write_text(CONFIG.format(instances=args.instances, repeats=args.repeats,
                                        unit_instances=args.unit_instances))
        arms = {
            "run": lambda: run_command(config, tmp / "run", None),
            "run1": lambda: run_command(config, tmp / "run1", 1),
            "plain": lambda: plain_loop(episodes),
        }
        for arm in arms.values():  # warm-up: file cache, bytecode
            arm()
        times: dict[str, list[float]] = {name: [] for name in arms}
        load = []
        for _ in range(args.rounds):
            for name, arm in arms.items():
                load.append(os.getloadavg()[0])
                times[name].append(arm())
    t_plain = statistics.median(times["plain"])
    print(f"{episodes} episodes x 8 taps, N = 1024, analytic insertion, {args.instances // args.unit_instances} units "
          f"(median of {args.rounds} interleaved rounds; load average {min(load):.1f}-{max(load):.1f} on "
          f"{os.cpu_count()} CPUs)")
    print(f"  plain per-episode NumPy loop (its loop only, one thread):   {t_plain:6.2f} s")
    for arm, label in (("run1", "probecommit run --threads 1 (a process)"),
                       ("run", "probecommit run as shipped (a process)")):
        t_run = statistics.median(times[arm])
        per_round = [p / r for r, p in zip(times[arm], times["plain"])]
        print(f"  {label + ':':59s} {t_run:6.2f} s   plain / run = {t_plain / t_run:.2f}x "
              f"(rounds {min(per_round):.2f}-{max(per_round):.2f})  (target: >= 3)")


if __name__ == "__main__":
    main()
