"""Where `probecommit run`'s CPU goes on the end-to-end config (issue 42, target 1): CPU seconds of
the imports and of each coarse piece of ``run_study`` (rollouts, filter updates, commits, belief
summaries, unit tables, writes, finalize), one thread, in this process.

Wrappers on a few coarse calls (hundreds of calls in all), not a profiler: a profiler's per-call
cost inflates the pieces made of many small calls (the rollout's per-tap engine calls) several
fold. Nested pieces are indented under the piece that calls them; a piece's time includes theirs.

    python benchmarks/run_parts.py [--instances 480] [--repeats 4]
"""

from __future__ import annotations

import argparse
import collections
import functools
import shutil
import sys
import tempfile
import time
from pathlib import Path

T0 = time.process_time()
import probecommit.core.belief as core_belief  # noqa: E402
import probecommit.core.executors as core_executors  # noqa: E402
import probecommit.runner.inference as inference  # noqa: E402
import probecommit.runner.study as study  # noqa: E402
import probecommit.store.rundir as rundir  # noqa: E402
from probecommit.process.memory import reuse_freed_arrays  # noqa: E402
from probecommit.runner.config import load_config  # noqa: E402

IMPORTS = time.process_time() - T0
sys.path.insert(0, str(Path(__file__).resolve().parent))
from end_to_end import CONFIG  # noqa: E402

CPU: collections.Counter = collections.Counter()
PIECES = [  # (owner, attribute, label): the label's indent shows what it is part of
    (study, "rollout", "rollout (taps drawn, engine answers)"),
    (study, "build_trace", "beliefs (build_trace)"),
    (core_belief.ParticleFilter, "initial", "  prior particles drawn"),
    (core_belief.ParticleFilter, "update", "  filter updates"),
    (study, "commit", "commits and episode columns"),
    (inference, "_belief_at", "  decision coordinates made contiguous"),
    (inference, "_belief_summary", "  belief summaries (hull, coverage score, variance)"),
    (inference, "_execute", "  actions executed"),
    (study, "_split_group", "unit tables (a group's, sliced)"),
    (rundir.RunDir, "add_unit", "units kept"),
    (rundir.RunDir, "commit_if_due", "batches written (group commit)"),
    (rundir.RunDir, "finalize", "finalize (final tables, manifest)"),
    (rundir.RunDir, "final_episodes_table", "episodes table for the result"),
]


def _timed(owner, name: str, label: str) -> None:
    fn = getattr(owner, name)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            CPU[label] += time.process_time() - start

    setattr(owner, name, wrapper)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=480)
    ap.add_argument("--repeats", type=int, default=4)
    args = ap.parse_args()
    reuse_freed_arrays()  # as the command does
    for owner, name, label in PIECES:
        _timed(owner, name, label)
    for cls in vars(core_executors).values():
        if isinstance(cls, type) and "decide" in vars(cls):
            _timed(cls, "decide", "  executors decide")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "e2e.yaml"
        path.write_text(CONFIG.format(instances=args.instances, repeats=args.repeats, unit_instances=4))
        config = load_config(path)
        start = time.process_time()
        study.run_study(config, Path(tmp) / "run", threads=1)
        total = time.process_time() - start
        shutil.rmtree(Path(tmp) / "run", ignore_errors=True)
    print(f"CPU seconds, {args.instances * args.repeats} episodes, one thread:")
    print(f"  {'imports (runner, store, core; not the CLI)':54s} {IMPORTS:6.3f}")
    print(f"  {'run_study':54s} {total:6.3f}")
    for label in [p[2] for p in PIECES[:6]] + ["  executors decide"] + [p[2] for p in PIECES[6:]]:
        print(f"    {label:52s} {CPU[label]:6.3f}")


if __name__ == "__main__":
    main()
