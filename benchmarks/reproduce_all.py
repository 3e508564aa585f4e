"""Benchmark (issue 42, target 4): `probecommit reproduce all` in <= 3 min and <= 500 MB on an idle 2-core machine.

Runs ``probecommit reproduce all --workers W`` (W = 2 by default: independent targets side by
side) as a process into a fresh folder (nothing published), and measures its wall time, its
CPU (user + sys of the process tree), and the peak memory of the whole process tree (the sum
of the resident sets of the command and every process it started, sampled every 0.2 s).
Prints each target's wall time (``reproduction.json``), the totals against the target, and,
with ``--compare DIR`` (a finished reproduction's root, e.g. a frozen full run), whether
every target's ``results.json`` holds the same numbers, key by key.

    python benchmarks/reproduce_all.py                           # the target (minutes)
    python benchmarks/reproduce_all.py --quick                   # the pipeline on a few instances
    python benchmarks/reproduce_all.py --compare /tmp/rall --keep runs/rall-2
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def tree_rss(pid: int) -> int:
    """Resident bytes of ``pid`` and every process under it (Linux ``/proc``; 0 where unreadable)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        todo += children.get(p, [])
        try:
            for line in (Path("/proc") / str(p) / "status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1]) * 1024
        except OSError:
            pass
    return total


def flatten(value: Any, prefix: str = "") -> dict[str, Any]:
    """``results.json`` as ``{dotted.key: leaf}``."""
    if isinstance(value, dict):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(flatten(item, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list):
        out = {}
        for i, item in enumerate(value):
            out.update(flatten(item, f"{prefix}[{i}]"))
        return out
    return {prefix: value}


def same(a: Any, b: Any) -> bool:
    """Equal leaves (NaN equals NaN)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def compare(root: Path, reference: Path) -> list[str]:
    """One line per target: how many numbers of ``results.json`` differ from the reference's."""
    lines = []
    for results in sorted(reference.glob("*/results/results.json")):
        target = results.parent.parent.name
        mine = root / target / "results" / "results.json"
        if not mine.is_file():
            lines.append(f"{target}: no results.json here")
            continue
        # The numbers (``results``): not the figure paths, wall times or engine-query counts beside them.
        a = flatten(json.loads(mine.read_text()).get("results", {}))
        b = flatten(json.loads(results.read_text()).get("results", {}))
        differ = sorted(k for k in set(a) | set(b) if k not in a or k not in b or not same(a[k], b[k]))
        shown = ", ".join(differ[:5]) + (" ..." if len(differ) > 5 else "")
        lines.append(f"{target}: {len(b)} numbers, {len(differ)} differ" + (f" ({shown})" if differ else ""))
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--compare", type=Path, help="A finished reproduction's root to compare results.json with.")
    ap.add_argument("--keep", type=Path, help="Reproduce into this folder (kept) instead of a temporary one.")
    args = ap.parse_args()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "COLUMNS": "120"}
    with tempfile.TemporaryDirectory() as tmp_name:
        root = args.keep or Path(tmp_name) / "paper"
        cmd = [sys.executable, "-m", "probecommit", "reproduce", "all", "--out", str(root), "--workers",
               str(args.workers), "--no-publish"] + (["--quick"] if args.quick else [])
        load, peak = [os.getloadavg()[0]], 0
        usage0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        while proc.poll() is None:
            peak = max(peak, tree_rss(proc.pid))
            time.sleep(0.2)
        wall = time.perf_counter() - start
        stderr = proc.stderr.read() if proc.stderr else ""
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = usage.ru_utime + usage.ru_stime - usage0.ru_utime - usage0.ru_stime
        load.append(os.getloadavg()[0])
        if proc.returncode != 0:
            raise SystemExit(f"reproduce failed (exit {proc.returncode}): {stderr.strip().splitlines()[-3:]}")
        record = json.loads((root / "reproduction.json").read_text())
        lines = compare(root, args.compare) if args.compare else []
    print(f"probecommit reproduce all{' --quick' if args.quick else ''} --workers {args.workers} "
          f"(load average {min(load):.1f}-{max(load):.1f} on {os.cpu_count()} CPUs; "
          f"{record.get('side_by_side', 1)} targets at once)")
    for name, seconds in record["wall_s"].items():
        print(f"  {name:10s} {seconds:7.1f} s")
    print(f"  wall {wall:.0f} s, CPU {cpu:.0f} s, peak memory of the process tree {peak / 2**20:.0f} MB")
    for line in lines:
        print(f"  same numbers as {args.compare}: {line}")
    if not args.quick:
        print(f"  target (issue 42): <= 180 s and <= 500 MB on an idle 2-core machine -> "
              f"{'met' if wall <= 180 and peak <= 500 * 2**20 else 'MISSED'}")


if __name__ == "__main__":
    main()
