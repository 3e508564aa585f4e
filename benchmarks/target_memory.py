"""Benchmark: the peak resident memory of each process of one reproduction target, as ``reproduce all --workers 2`` runs it.

Usage::

    python benchmarks/target_memory.py breadth --inputs runs/paper --root /tmp/mem     # one target, fresh
    python benchmarks/target_memory.py explain --inputs runs/paper --root /tmp/mem --stacks

``--inputs`` is a finished reproduction's root: every target folder but this one is copied under ``--root``
(the targets it reads), so the target itself runs from nothing. It runs as a side-by-side lane does
(``report.schedule.run_target``, one worker, the command's Arrow pool and heap thresholds) in a child
process; the resident memory (``VmRSS``) of that process and of every process it starts (explain's steps
set aside, worker pools) is read from ``/proc`` every 0.2 s, and its peak (``VmHWM``, the kernel's high-water
mark, so no spike falls between polls). Printed: each process's peak (MB) and when it was first seen,
the largest sum over the tree, wall seconds and the load average at start and end (peaks hardly depend
on load; times do). ``--stacks``: a ``py-spy dump`` of a process each time its peak grows by ``--stacks-step``
MB (40) from ``--stacks-from`` MB (250) (where it was when it grew), when py-spy is installed. ``--json PATH`` writes it all.
Linux only (``/proc``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

LANE = """
import sys
from probecommit.cli.app import use_system_arrow_pool
from probecommit.process.memory import reuse_freed_arrays
if __name__ == "__main__":
    use_system_arrow_pool(); reuse_freed_arrays()
    from probecommit.report.schedule import run_target
    print(run_target(sys.argv[1], sys.argv[2], False, 1, {}))
"""


def tree_rss(root_pid: int, field: str = "VmRSS") -> dict[int, int]:
    """``field`` (MB; VmRSS now, VmHWM the kernel's peak so far) of ``root_pid`` and every process below it."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            children.setdefault(int(stat.rsplit(")", 1)[1].split()[1]), []).append(int(entry))
    out, stack = {}, [root_pid]
    while stack:
        pid = stack.pop()
        stack += children.get(pid, [])
        try:
            line = next(x for x in Path(f"/proc/{pid}/status").read_text().splitlines() if x.startswith(field + ":"))
        except (OSError, StopIteration):
            continue
        out[pid] = int(line.split()[1]) // 1024
    return out


def command_line(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()[:120]
    except OSError:
        return "?"


def parent(pid: int) -> int:
    """``pid``'s parent (0 once it is gone)."""
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return 0


def sample(argv: list[str], stacks: bool, poll_s: float = 0.2, stacks_from: int = 250, stacks_step: int = 40,
           env: dict[str, str] | None = None) -> dict:
    """Run ``argv``, sampling its process tree; the per-process peaks, parents and resident memory over time.

    ``stacks``: a ``py-spy dump`` of a process each time its peak grows by ``stacks_step`` MB from ``stacks_from``.
    """
    spy = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    proc = subprocess.Popen(argv, env=env)
    start, peaks, dumps, dumped, most, parents, series = time.perf_counter(), {}, [], {}, 0, {}, {}
    while proc.poll() is None:
        now = round(time.perf_counter() - start, 1)
        sizes = tree_rss(proc.pid)
        most = max(most, sum(sizes.values()))
        for pid, mb in sizes.items():  # resident memory over time, a point each time it moves by 10 MB
            parents.setdefault(pid, parent(pid))
            if not series.get(pid) or abs(series[pid][-1][1] - mb) >= 10:
                series.setdefault(pid, []).append((now, mb))
        for pid, mb in tree_rss(proc.pid, "VmHWM").items():  # the kernel's peak: no spike falls between polls
            if mb > peaks.get(pid, (0,))[0]:
                peaks[pid] = (mb, now, command_line(pid))
                if stacks and mb >= stacks_from and mb >= dumped.get(pid, 0) + stacks_step and Path(spy).exists():
                    dumped[pid] = mb
                    dump = subprocess.run([spy, "dump", "--nonblocking", "--pid", str(pid)], capture_output=True,
                                          text=True, timeout=60).stdout
                    dumps.append({"s": now, "pid": pid, "mb": mb, "stack": dump})
        time.sleep(poll_s)
    return {"rc": proc.returncode, "wall_s": round(time.perf_counter() - start, 1), "tree_sum_peak_mb": most,
            "processes": sorted(([mb, s, pid, cmd] for pid, (mb, s, cmd) in peaks.items()), reverse=True),
            "stacks": dumps, "root_pid": proc.pid, "parents": parents, "series": series}


def measure(argv: list[str], args: argparse.Namespace, label: str, names: Callable[[dict], dict[int, str]] | None = None,
            env: dict[str, str] | None = None, extra: dict | None = None) -> dict:
    """:func:`sample` of ``argv`` with ``args``' stack settings; prints its largest processes (named by ``names(result)``,
    else by their command lines) and writes ``args.json``. The result."""
    load = os.getloadavg()
    result = sample(argv, args.stacks, 0.2, args.stacks_from, args.stacks_step, env)
    named = names(result) if names else {}
    result.update(extra or {}, load_start=load, load_end=os.getloadavg(), targets={str(k): v for k, v in named.items()})
    for mb, s, pid, cmd in result["processes"][:12]:
        print(f"{mb:6d} MB at {s:8.1f} s  pid {pid}  {named.get(pid, cmd)}")
    print(f"{label}: rc {result['rc']}, wall {result['wall_s']} s, largest process {result['processes'][0][0]} MB, "
          f"tree sum {result['tree_sum_peak_mb']} MB, load {load[0]:.1f} -> {result['load_end'][0]:.1f}")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("target")
    parser.add_argument("--inputs", required=True, help="a finished reproduction's root (the targets it reads)")
    parser.add_argument("--root", required=True, help="a scratch root (replaced)")
    parser.add_argument("--stacks", action="store_true")
    parser.add_argument("--stacks-from", type=int, default=250, help="MB: the first py-spy dump at this peak")
    parser.add_argument("--stacks-step", type=int, default=40, help="MB: another dump each time the peak grows this much")
    parser.add_argument("--json")
    args = parser.parse_args()
    root = Path(args.root)
    shutil.rmtree(root, ignore_errors=True)
    root.mkdir(parents=True)
    for folder in Path(args.inputs).iterdir():
        if folder.is_dir() and folder.name != args.target:
            shutil.copytree(folder, root / folder.name)
    lane = root / "_lane.py"
    lane.write_text(LANE)
    result = measure([sys.executable, str(lane), args.target, str(root)], args, args.target, extra={"target": args.target})
    sys.exit(result["rc"])


if __name__ == "__main__":
    main()
