"""Benchmark: `calibrate` on a Split-B-size pair, side by side in one run, identical output.

Usage::

    python benchmarks/calibrate.py                # this tree: reuse + kernel vs per-commit recomputation in NumPy
    python benchmarks/calibrate.py --against REF  # ... and a git ref (e.g. 01b9326) timed in a subprocess

Both pairs are analytic insertion runs of 96 instances x 4 repeats, random taps,
k = 1..8, N = 1024 (the paper's Split B size), made once into a temporary folder.
Prints each arm's wall time, the ratios, and whether the calibration results are
identical (the JSON of ``CalibrationResult.to_dict``).
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline import baseline_tree  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIG = """name: {name}
task: insertion
seed: 2026
repeats: 4
instances: {{split: {split}, count: 96, seed: 103}}
probes: {{schedule: random, budget: 8}}
belief: {{particles: 1024, nu: 0.8}}
simulator: {{engine: analytic}}
"""

ARM = """
import json, sys, time
from probecommit.runner.config import load_config
from probecommit.runner.study import run_study
{calibrate_import}
out = sys.argv[1]
for split in ("B_cal", "B_test"):
    run_study(load_config(f"{{out}}/{{split}}.yaml"), f"{{out}}/{{split}}")
t0 = time.perf_counter()
result = calibrate(f"{{out}}/B_cal", f"{{out}}/B_test"{extra})
print(json.dumps({{"seconds": time.perf_counter() - t0, "result": result.to_dict()}}, default=str, sort_keys=True))
"""


def run_arm(src: Path, out: Path, calibrate_import: str, extra: str = "", env: dict | None = None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    for split in ("B_cal", "B_test"):
        (out / f"{split}.yaml").write_text(CONFIG.format(name=split, split=split))
    code = ARM.format(calibrate_import=calibrate_import, extra=extra)
    environment = {**os.environ, "PYTHONPATH": str(src), **(env or {})}
    done = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, env=environment,
                          check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", help="A git ref to time as the baseline (checked out into a temporary worktree).")
    args = parser.parse_args()
    src = ROOT / "src"
    new_import = "from probecommit.runner.calibration import calibrate"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        arms = {
            "this tree (reuse + numba kernel)": run_arm(src, tmp / "a", new_import),
            "this tree, reference path (recompute per commit, NumPy)": run_arm(
                src, tmp / "b", new_import, ", reuse=False", {"PROBECOMMIT_KERNELS": "numpy"}),
        }
        if args.against:
            with baseline_tree(args.against, tmp / "baseline") as tree:
                old_import = ("try:\n    from probecommit.runner.calibration import calibrate\n"
                              "except ImportError:\n    from probecommit.audit.pipeline import calibrate")
                arms[f"git {args.against}"] = run_arm(tree / "src", tmp / "c", old_import)
    first = next(iter(arms.values()))
    print("calibrate on a Split-B-size pair (96 x 4, k = 1..8, N = 1024, analytic engine)")
    for name, arm in arms.items():
        same = json.dumps(arm["result"], sort_keys=True) == json.dumps(first["result"], sort_keys=True)
        print(f"  {name:58s} {arm['seconds']:7.2f} s   x{arm['seconds'] / first['seconds']:5.2f}   identical: {same}")


if __name__ == "__main__":
    main()
