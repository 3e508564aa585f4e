"""Benchmark (issue 42, target 2): a MuJoCo run's CPU against the CPU of its engine queries alone.

The study: MuJoCo insertion, ``--instances`` x 4 repeats (96 x 4, Split B's size, by
default), random taps, k = 1..8, N = 1024, Probe-Robust only. ``probecommit run`` is timed
as a process (CPU = user + sys of the process and its children: start-up, imports,
rollouts, beliefs, commits, writes). The floor: every distinct engine query the run made
(its ``engine_cache.parquet``: probes and executions), run again in a fresh process through
the run's own simulator, one after the other, CPU of that loop alone (no start-up, no
imports). Prints both, the ratio and the target (<= 1.25). The package's bytecode is compiled
first and the processes may load it, as from a user's install (``as_user.py``).

    python benchmarks/mujoco_overhead.py [--instances 96] [--threads 1]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from as_user import children_cpu, compile_tree, user_env  # noqa: E402

CONFIG = """name: mujoco-overhead
task: insertion
seed: 2026
repeats: 4
instances: {{split: B_cal, count: {instances}, seed: 103}}
probes: {{schedule: random, budget: 8}}
belief: {{particles: 1024, nu: 0.8}}
simulator: {{engine: mujoco}}
methods: [probe_robust]
"""

QUERIES_ALONE = """
import json, sys, time
import pandas as pd
from probecommit.runner.config import load_config
from probecommit.runner import build
run = sys.argv[1]
config = load_config(run + "/config.yaml")
simulator = build.build_simulator(config)
latents = build.build_model(config).latent_names
cache = pd.read_parquet(run + "/engine_cache.parquet")
theta = cache[list(latents)].to_numpy(float)
keys = [(q, tuple(float(v) for v in t), tuple(float(v) for v in a)) for q, t, a in zip(cache["query"], theta, cache["arg"])]
c0, t0 = time.process_time(), time.perf_counter()
for key in keys:
    simulator._engine_answer(key)
print(json.dumps({"cpu": time.process_time() - c0, "wall": time.perf_counter() - t0, "queries": len(keys)}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=96)
    ap.add_argument("--threads", type=int, default=1, help="The run's --threads (1: its CPU is not inflated by "
                                                          "two threads contending; the floor runs one thread).")
    args = ap.parse_args()
    env = user_env(ROOT / "src", COLUMNS="120")
    compile_tree(ROOT / "src")
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        (tmp / "c.yaml").write_text(CONFIG.format(instances=args.instances))
        c0, t0 = children_cpu(), time.perf_counter()
        subprocess.run([sys.executable, "-m", "probecommit", "run", str(tmp / "c.yaml"), "--out", str(tmp / "run"),
                        "--threads", str(args.threads)], env=env, check=True, capture_output=True)
        run_cpu, run_wall = children_cpu() - c0, time.perf_counter() - t0
        load.append(os.getloadavg()[0])
        done = subprocess.run([sys.executable, "-c", QUERIES_ALONE, str(tmp / "run")], env=env, check=True,
                              capture_output=True, text=True)
        alone = json.loads(done.stdout.strip().splitlines()[-1])
        manifest = json.loads((tmp / "run" / "manifest.json").read_text())
        load.append(os.getloadavg()[0])
    calls = sum(int(v) for v in (manifest.get("engine_calls") or {}).values())
    print(f"MuJoCo insertion run, {args.instances} x 4 episodes x 8 taps, N = 1024, --threads {args.threads} "
          f"(load average {min(load):.1f}-{max(load):.1f} on {os.cpu_count()} CPUs)")
    print(f"  probecommit run (a process, CPU):          {run_cpu:7.2f} s   (wall {run_wall:.2f} s; "
          f"{calls} engine queries run, {alone['queries']} distinct answers stored)")
    print(f"  its engine queries alone (CPU of the loop): {alone['cpu']:7.2f} s")
    ratio = run_cpu / alone["cpu"]
    print(f"  run / queries alone = {ratio:.2f}x   target (issue 42): <= 1.25 -> {'met' if ratio <= 1.25 else 'MISSED'}")


if __name__ == "__main__":
    main()
