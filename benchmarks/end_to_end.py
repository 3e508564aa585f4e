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
threads, one per CPU up to 4) and with ``--threads 1``. The package's bytecode is compiled
first and the processes may load it, as from a user's install (``as_user.py``). The arms take turns for ``--rounds``
rounds after a warm-up; medians, ratios of the medians and the range of per-round ratios are
printed, with the load average. With ``--against REF`` the two ``run`` arms of a git ref (checked
out beside this tree, its kernels built) take turns with this tree's too, and the ratios ref / this
tree are printed: a change measured side by side on the same loaded machine.

    python benchmarks/end_to_end.py [--instances 480] [--repeats 4] [--rounds 3] [--unit-instances 4] [--against REF]

Target: plain / run >= 3 (the run at least three times as fast) on an idle 2-core machine.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from as_user import children_cpu, compile_tree, user_env  # noqa: E402
from baseline import baseline_tree  # noqa: E402

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
t0, c0 = time.perf_counter(), time.process_time()
run_plain(model, u, y, list(range(episodes)), 1024)
print(json.dumps({{"seconds": time.perf_counter() - t0, "cpu": time.process_time() - c0}}))
"""


def run_command(config: Path, out: Path, threads: int | None, src: Path = ROOT / "src") -> tuple[float, float]:
    """Wall and CPU seconds of ``probecommit run`` (the package under ``src``) as a process, into a fresh ``out``."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-m", "probecommit", "run", str(config), "--out", str(out)]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    env = user_env(src, COLUMNS="120")
    t0, c0 = time.perf_counter(), children_cpu()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True)
    return time.perf_counter() - t0, children_cpu() - c0


def plain_loop(episodes: int) -> tuple[float, float]:
    """Wall and CPU seconds of the plain loop alone, in a process of its own."""
    code = PLAIN.format(here=str(HERE), episodes=episodes)
    env = user_env(ROOT / "src")
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    out = json.loads(done.stdout.strip().splitlines()[-1])
    return out["seconds"], out["cpu"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=480)
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--unit-instances", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--against", help="a git ref whose run arms take turns with this tree's")
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
        compile_tree(ROOT / "src")
        with (baseline_tree(args.against, tmp / "ref") if args.against else contextlib.nullcontext()) as ref:
            if ref is not None:
                compile_tree(ref / "src")
                arms["run@ref"] = lambda: run_command(config, tmp / "run-ref", None, ref / "src")
                arms["run1@ref"] = lambda: run_command(config, tmp / "run1-ref", 1, ref / "src")
            times, load = _interleaved(arms, args.rounds)
    print(f"{episodes} episodes x 8 taps, N = 1024, analytic insertion, {args.instances // args.unit_instances} units "
          f"(median of {args.rounds} interleaved rounds; load average {min(load):.1f}-{max(load):.1f} on "
          f"{os.cpu_count()} CPUs)")
    for what, i in (("wall", 0), ("CPU", 1)):
        t_plain = statistics.median(t[i] for t in times["plain"])
        print(f"  {what} time: plain per-episode NumPy loop (its loop only, one thread): {t_plain:6.2f} s")
        for arm, label in (("run1", "probecommit run --threads 1 (a process)"),
                           ("run", "probecommit run as shipped (a process)")):
            t_run = statistics.median(t[i] for t in times[arm])
            per_round = [p[i] / r[i] for r, p in zip(times[arm], times["plain"])]
            print(f"  {what} time: {label + ':':56s} {t_run:6.2f} s   plain / run = {t_plain / t_run:.2f}x "
                  f"(rounds {min(per_round):.2f}-{max(per_round):.2f})  (target: >= 3 in wall time, idle)")
    print("  (on a loaded machine wall times measure the share of the CPUs each process got; CPU times do not)")
    for arm in ("run", "run1"):
        if f"{arm}@ref" in times:
            for what, i in (("wall", 0), ("CPU", 1)):
                ratio = statistics.median(t[i] for t in times[f"{arm}@ref"]) / statistics.median(t[i] for t in times[arm])
                print(f"  {what} time: {arm} at {args.against} / this tree = {ratio:.2f}x")


def _interleaved(arms: dict, rounds: int) -> tuple[dict[str, list[tuple[float, float]]], list[float]]:
    """Each arm once to warm up (file cache, bytecode), then ``rounds`` rounds of every arm in turn."""
    for arm in arms.values():
        arm()
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in arms}
    load = []
    for _ in range(rounds):
        for name, arm in arms.items():
            load.append(os.getloadavg()[0])
            times[name].append(arm())
    return times, load

if __name__ == "__main__":
    main()
