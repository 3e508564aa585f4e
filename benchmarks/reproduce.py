"""Benchmark: `probecommit reproduce insertion` (MuJoCo) against a git ref, side by side.

Usage::

    python benchmarks/reproduce.py --against 01b9326   # the code when issue 15 was filed

Each arm runs the whole insertion reproduction once, in a fresh process, into its own
temporary folder: this tree from ``src/``, the ref from a temporary worktree. The
printed numbers are each arm's wall time and peak resident memory (``ru_maxrss`` of
that process, from ``os.wait4``), their ratio, and whether every number of the two
``results.json`` files is the same (wall time, figure paths and engine-call counts
left out: those are what the work changes). About 6 minutes on a 2-core machine with
the baseline arm, so it is not part of ``make bench``; nothing else should run meanwhile.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline import baseline_tree  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: Keys of results.json that are not results (they are what a faster reproduction changes).
NOT_RESULTS = ("wall_s", "figures", "engine_calls")

ARM = """
import sys
from probecommit.cli.app import main
sys.argv = ["probecommit", "reproduce", "insertion", "-o", sys.argv[1], *sys.argv[2:]]
main()
"""


def run_arm(src: Path, out: Path, workdir: Path) -> dict[str, Any]:
    """Run the reproduction from ``src`` into ``out``; wall seconds, peak MB and the results."""
    # Older code has no --no-publish; it then publishes into its own (temporary) worktree.
    help_text = subprocess.run([sys.executable, "-c", ARM, str(out), "--help"], capture_output=True, text=True,
                               cwd=workdir, env={**os.environ, "PYTHONPATH": str(src)}).stdout
    extra = ["--no-publish"] if "--no-publish" in help_text else []
    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-c", ARM, str(out), *extra], cwd=workdir, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, env={**os.environ, "PYTHONPATH": str(src)})
    _, status, usage = os.wait4(child.pid, 0)
    seconds = time.perf_counter() - start
    if status:
        raise RuntimeError(f"reproduce insertion from {src} failed:\n{child.stderr.read().decode()[-3000:]}")
    found = sorted(out.rglob("results.json"))
    if not found:
        raise RuntimeError(f"reproduce insertion from {src} wrote no results.json under {out}")
    payload = json.loads(found[0].read_text())
    return {"seconds": seconds, "peak_mb": usage.ru_maxrss / 1024, "payload": payload}


def differences(a: Any, b: Any, path: str = "") -> list[str]:
    """Paths where two JSON values differ (NaN equals NaN)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}/{k}: only in one" for k in set(a) ^ set(b)]
        for key in sorted(set(a) & set(b)):
            if not path and key in NOT_RESULTS:
                continue
            out += differences(a[key], b[key], f"{path}/{key}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{path}[{i}]")]
    same = a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))
    return [] if same else [f"{path}: {a!r} vs {b!r}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", help="A git ref run as the baseline (checked out into a temporary worktree).")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        arms = {"this tree": (ROOT / "src", ROOT)}
        with contextlib.ExitStack() as stack:
            if args.against:
                tree = stack.enter_context(baseline_tree(args.against, tmp / "baseline"))
                arms = {f"git {args.against}": (tree / "src", tree), **arms}
            results = {name: run_arm(src, tmp / f"out{i}", workdir) for i, (name, (src, workdir)) in enumerate(arms.items())}
    print("probecommit reproduce insertion (MuJoCo), each arm a fresh process, one after the other")
    for name, r in results.items():
        calls = r["payload"].get("engine_calls", {})
        print(f"  {name:>16}: {r['seconds']:6.1f} s wall, {r['peak_mb']:5.0f} MB peak, engine queries {calls}")
    if len(results) == 2:
        (base_name, base), (_, new) = results.items()
        diff = differences(base["payload"], new["payload"])
        print(f"  speed-up {base['seconds'] / new['seconds']:.2f}x (target >= 3), peak {new['peak_mb']:.0f} MB "
              f"(target < 400)")
        print(f"  results.json: {'every number identical' if not diff else f'{len(diff)} differences'}")
        for line in diff[:20]:
            print("    " + line)


if __name__ == "__main__":
    main()
