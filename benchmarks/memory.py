"""Benchmark: peak memory of `replay` and `calibrate` at E = 384 and 3072 episodes, side by side.

Usage::

    python benchmarks/memory.py                # this tree: chunked (default) vs one chunk per run
    python benchmarks/memory.py --against REF  # ... and a git ref (e.g. bd8b117) in a temporary worktree
    python benchmarks/memory.py --sizes 384 3072 12288 --repeat 3 --chunked-only   # the slope, medians of 3

The runs are analytic insertion runs of 96 and 768 instances x 4 repeats (``--sizes``: other
episode counts, multiples of 4), random taps, k = 1..8, N = 1024 (a calibration and a test run
per size), made once into a temporary folder. Each case runs in a fresh subprocess, with the Arrow memory pool the
``probecommit`` command uses (``ARROW_DEFAULT_MEMORY_POOL=system`` unless set) and its heap thresholds
(``MALLOC_MMAP_THRESHOLD_`` 32 MiB and ``MALLOC_TRIM_THRESHOLD_`` 256 MiB unless set), which reports its own peak
resident memory (``ru_maxrss``) and wall time, so the numbers are independent, and the
resident memory once ``load_run`` has opened its input runs (this tree reads only their
instances there, and the other tables when a replay or calibration asks; older code read every
table): the peak above it is what the work itself adds. ``replay`` writes the calibration run
re-inferred under the corrected model to a new run directory (``replay_run``, what ``probecommit
replay`` runs: each chunk's episodes go to disk when the chunk is done); ``replay_episodes`` is the
same replay through the in-memory API, which returns the whole table (so its peak holds its
output); a calibration calibrates on one run and tests on the other. Every arm's output is compared with
the first arm's: calibration JSON (``CalibrationResult.to_dict``), the replay's episodes and
engine cache read back, the returned table (pandas hash of every cell, dtypes included). Each line ends with the peak's growth
from each size to the next, in per cent and per added episode (of each run); with ``--repeat N``
each cell is the median of N processes (a peak varies by about 2 MB from one to the next). Printed
last, per size: the table ``replay_episodes`` returns, and the input a run's chunked beliefs hold from start to end
(the probe arrays of every episode and the run's engine answers as Arrow columns).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline import baseline_tree  # noqa: E402

from probecommit.process.memory import heap_environment  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SIZES = (384, 3072)  # episodes (4 repeats of each instance)
CONFIG = """name: {name}
task: insertion
seed: 2026
repeats: 4
instances: {{split: {split}, count: {count}, seed: 103}}
probes: {{schedule: random, budget: 8}}
belief: {{particles: 1024, nu: 0.8}}
simulator: {{engine: analytic}}
"""

MAKE = """
import sys
from probecommit.runner.config import load_config
from probecommit.runner.study import run_study
out = sys.argv[1]
for name in sys.argv[2:]:
    run_study(load_config(f"{out}/{name}.yaml"), f"{out}/{name}")
"""

CASE = """
import gc, hashlib, json, resource, shutil, sys, tempfile, time
import pandas as pd
from probecommit.runner.replay import load_run
case, cal, test, chunk = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
kwargs = {} if chunk == "default" else {"chunk_instances": None if chunk == "none" else int(chunk)}

def held_input_mb():
    # The probe arrays and stored engine answers a chunked RunBeliefs of the (first) run holds.
    try:
        from probecommit.runner.replay import RunBeliefs
        beliefs = RunBeliefs.of(runs[0])
        batch = beliefs.batch
        answers = sum(table.nbytes for table, _ in beliefs.answers._parts) if beliefs.answers else 0
    except (ImportError, AttributeError):
        return None
    arrays = (batch.u, batch.y, batch.truths, batch.context, batch.instance_index, batch.repeat, batch.instance_id)
    return (sum(a.nbytes for a in arrays) + answers) / 2**20


def resident_mb():
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[1]) * resource.getpagesize() / 2**20

t0 = time.perf_counter()
runs = [load_run(cal)] + ([load_run(test)] if case == "calibrate" else [])  # the input, which grows with E
gc.collect()
try:
    from probecommit.process.memory import trim_heap
    trim_heap()
except ImportError:
    pass
loaded_mb = resident_mb()
if case == "calibrate":
    try:
        from probecommit.runner.calibration import calibrate
    except ImportError:
        from probecommit.audit.pipeline import calibrate
    output = json.dumps(calibrate(*runs, **kwargs).to_dict(), default=str, sort_keys=True)
elif case == "replay":  # what `probecommit replay` runs: a new run directory
    from probecommit.runner.replay import replay_run
    out = tempfile.mkdtemp()
    replay_run(cal, f"{out}/replay", {"model": {"boundary": "corrected"}}, **kwargs)
else:  # the in-memory API: the whole table returned
    from probecommit.runner.replay import replay_episodes
    table, _ = replay_episodes(runs[0], {"model": {"boundary": "corrected"}}, **kwargs)
seconds = time.perf_counter() - t0
peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # before the output is read back


def digest(table):
    table = table.assign(**{c: table[c].map(tuple) for c in ("arg", "value") if c in table})
    return str(table.dtypes.to_dict()) + hashlib.sha256(pd.util.hash_pandas_object(table).to_numpy().tobytes()).hexdigest()


returned_mb = 0.0
if case == "replay":
    output = "".join(digest(pd.read_parquet(f"{out}/replay/{name}.parquet")) for name in ("episodes", "engine_cache"))
    shutil.rmtree(out)
elif case == "replay_episodes":
    output, returned_mb = digest(table), table.memory_usage(deep=True).sum() / 2**20
print(json.dumps({"seconds": seconds, "peak_mb": peak_mb, "loaded_mb": loaded_mb, "returned_mb": returned_mb,
                  "digest": hashlib.sha256(output.encode()).hexdigest(), "held_input_mb": held_input_mb()}))
"""

CASES = ("replay", "replay_episodes", "calibrate")


def make_runs(src: Path, out: Path, sizes: list[int]) -> None:
    names = []
    for episodes in sizes:
        for part in ("cal", "test"):
            name = f"{part}{episodes}"
            (out / f"{name}.yaml").write_text(CONFIG.format(name=name, split=f"B_{part}", count=episodes // 4))
            names.append(name)
    # A complete run directory is returned untouched, so a kept folder is reused.
    subprocess.run([sys.executable, "-c", MAKE, str(out), *names], check=True,
                   env={**os.environ, "PYTHONPATH": str(src)})


#: The Arrow memory pool of the cases: the one the ``probecommit`` command sets (``cli.app.use_system_arrow_pool``),
#: unless the caller's environment chose one.
ARROW_POOL = {"ARROW_DEFAULT_MEMORY_POOL": os.environ.get("ARROW_DEFAULT_MEMORY_POOL", "system")}
#: The heap thresholds the command sets (``process.memory.reuse_freed_arrays``), unless the caller's
#: environment chose them: every arm, a baseline's too, runs with the same allocator.
HEAP = heap_environment()


def run_case(src: Path, runs: Path, case: str, episodes: int, chunk: str, repeat: int = 1) -> dict:
    """The case's numbers, each the median of ``repeat`` fresh processes (their outputs must agree)."""
    done = [_run_once(src, runs, case, episodes, chunk) for _ in range(repeat)]
    if len({d["digest"] for d in done}) != 1:
        raise RuntimeError(f"{case} at E = {episodes} gave different outputs in repeated processes")
    return {key: (statistics.median(d[key] for d in done) if isinstance(done[0][key], float) else done[0][key])
            for key in done[0]}


def _run_once(src: Path, runs: Path, case: str, episodes: int, chunk: str) -> dict:
    done = subprocess.run([sys.executable, "-c", CASE, case, str(runs / f"cal{episodes}"), str(runs / f"test{episodes}"),
                           chunk], capture_output=True, text=True,
                          env={**os.environ, **ARROW_POOL, **HEAP, "PYTHONPATH": str(src)})
    if done.returncode:
        raise RuntimeError(f"{case} at E = {episodes} ({src}) exited with {done.returncode}: {done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", help="A git ref measured as the baseline (checked out into a temporary worktree).")
    parser.add_argument("--runs", type=Path, help="Keep the runs in this folder (and reuse them when complete).")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES),
                        help="Episodes per run, multiples of 4 (default: %(default)s).")
    parser.add_argument("--repeat", type=int, default=1, help="Fresh processes per case; cells are their medians.")
    parser.add_argument("--chunked-only", action="store_true",
                        help="Skip the one-chunk-per-run arm (about 0.3 MB per episode: 3.6 GB at E = 12288).")
    args = parser.parse_args()
    sizes = sorted(set(args.sizes))
    if any(e < 4 or e % 4 for e in sizes) or args.repeat < 1:
        parser.error("--sizes must be multiples of 4 (instances x 4 repeats) and --repeat at least 1")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        runs = args.runs or tmp / "runs"
        runs.mkdir(parents=True, exist_ok=True)
        make_runs(ROOT / "src", runs, sizes)
        arms = {"this tree, chunked (default)": (ROOT / "src", "default")}
        if not args.chunked_only:
            arms["this tree, one chunk per run"] = (ROOT / "src", "none")
        with contextlib.ExitStack() as stack:
            if args.against:
                tree = stack.enter_context(baseline_tree(args.against, tmp / "baseline"))
                arms[f"git {args.against}"] = (tree / "src", "default")
            results = {(case, episodes, arm): run_case(src, runs, case, episodes, chunk, args.repeat)
                       for case in CASES for episodes in sizes for arm, (src, chunk) in arms.items()}
    print("peak resident memory (ru_maxrss) of replay and calibrate, each case in a fresh process "
          f"(analytic insertion, 4 repeats, k = 1..8, N = 1024, {ARROW_POOL['ARROW_DEFAULT_MEMORY_POOL']} Arrow pool, "
          f"heap thresholds {int(HEAP['MALLOC_MMAP_THRESHOLD_']) / 2**20:g} MiB mmap, "
          f"{int(HEAP['MALLOC_TRIM_THRESHOLD_']) / 2**20:g} MiB trim"
          + (f"; medians of {args.repeat} processes" if args.repeat > 1 else "") + "); "
          "in brackets, the peak above the resident "
          "memory once load_run has opened the input runs (this tree reads their tables later, older code there)")
    first = next(iter(arms))
    for case in CASES:
        for arm in arms:
            cells = "   ".join(f"E = {e:5d}: {results[case, e, arm]['peak_mb']:7.1f} MB "
                               f"[+{results[case, e, arm]['peak_mb'] - results[case, e, arm]['loaded_mb']:6.1f}] "
                               f"{results[case, e, arm]['seconds']:5.1f} s" for e in sizes)
            same = all(results[case, e, arm]["digest"] == results[case, e, first]["digest"] for e in sizes)
            steps = []
            for small, large in zip(sizes[:-1], sizes[1:]):
                low, high = results[case, small, arm]["peak_mb"], results[case, large, arm]["peak_mb"]
                steps.append(f"{high / low - 1:+6.1%} ({(high - low) * 1024 / (large - small):4.1f} KB per episode)")
            print(f"  {case:15s} {arm:30s} {cells}   growth {', then '.join(steps)}   identical: {same}")
    returned = ", ".join(f"{results['replay_episodes', e, first]['returned_mb']:.1f} MB at E = {e}" for e in sizes)
    print(f"  (the table replay_episodes returns, its output and part of its peak: {returned})")
    held = [results["replay", e, first]["held_input_mb"] for e in sizes]
    if None not in held:
        print("  (the input a run's chunked beliefs hold throughout, probe arrays and engine answers: "
              + ", ".join(f"{mb:.1f} MB at E = {e}" for mb, e in zip(held, sizes)) + "; calibrate holds two runs')")


if __name__ == "__main__":
    main()
