"""End to end (issue 15, target 7): `probecommit run` against a plain per-episode NumPy loop.

The study: analytic insertion, 480 instances x 4 repeats, random taps, k = 1..8,
N = 1024, Probe-Robust only (belief, executor and bookkeeping are all the work). The
plain loop (``benchmarks/belief.py``'s ``run_plain``, written independently of the
package) filters the same number of episodes with the same number of taps and commits
at every budget. ``run`` is timed twice: as a user gets it (units in threads, one per CPU
up to 4, the simulator being thread-safe) and in one thread (``threads=1``), the plain loop
always using one. All arms run in this process after a warm-up, then take turns for
``--rounds`` rounds; the medians and the ratios of the medians (with the range of the
per-round ratios) are printed. The process keeps freed arrays in its heap as the
``probecommit`` command does (``core.memory.reuse_freed_arrays``); ``--default-heap`` leaves
glibc's defaults.

    python benchmarks/end_to_end.py [--instances 480] [--repeats 4] [--rounds 3] [--default-heap]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from belief import add_heap_option, heap_setting, interleaved, make_data, run_plain  # noqa: E402

from probecommit.runner.config import parse_config  # noqa: E402
from probecommit.runner.study import run_study, unit_threads  # noqa: E402


def study(instances: int, repeats: int):
    return parse_config({
        "name": "e2e", "seed": 7, "repeats": repeats,
        "instances": {"split": "e2e", "count": instances, "seed": 1},
        "probes": {"schedule": "random", "budget": 8}, "belief": {"particles": 1024},
        "simulator": {"engine": "analytic"}, "methods": ["probe_robust"], "unit_instances": 32,
    })


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=480)
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=3)
    add_heap_option(ap)
    args = ap.parse_args()
    heap = heap_setting(args)
    episodes = args.instances * args.repeats
    model, u, y = make_data(episodes, 8)
    with tempfile.TemporaryDirectory() as tmp:
        runs = iter(range(10**6))
        # Each call a fresh run folder (a complete one would be returned as it is).
        times, _ = interleaved({
            "run": lambda: run_study(study(args.instances, args.repeats), Path(tmp) / f"run{next(runs)}"),
            "run1": lambda: run_study(study(args.instances, args.repeats), Path(tmp) / f"run{next(runs)}", threads=1),
            "plain": lambda: run_plain(model, u, y, list(range(episodes)), 1024),
        }, args.rounds)
    threads = unit_threads(study(args.instances, args.repeats))
    t_plain = float(np.median(times["plain"]))
    print(f"{episodes} episodes x 8 taps, N = 1024, analytic insertion (median of {args.rounds} interleaved rounds, {heap})")
    print(f"  plain per-episode NumPy loop (filter + commit per tap, one thread): {t_plain:6.2f} s")
    for arm, label in (("run1", "probecommit run, one thread (threads=1)"),
                       ("run", f"probecommit run as shipped ({threads} unit threads)")):
        t_run = float(np.median(times[arm]))
        per_round = [r / p for r, p in zip(times[arm], times["plain"])]
        print(f"  {label + ':':56s} {t_run:6.2f} s   run / plain = {t_run / t_plain:.2f} "
              f"(rounds {min(per_round):.2f}-{max(per_round):.2f})  (target: <= 0.5)")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
