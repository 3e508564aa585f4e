"""Benchmark: which process of a whole ``probecommit reproduce all`` reaches its peak resident memory, and where.

Usage::

    python benchmarks/run_memory.py -o /tmp/mem_full --json /tmp/mem_full.json -- --workers 2 --publish-to /tmp/mem_pub

Runs ``python -m probecommit reproduce all -o OUT`` plus the arguments after ``--`` and polls every process of
its tree as ``target_memory.py`` does (``VmHWM``, the kernel's peak, so no spike falls between polls). Each
process is named by the target it runs: ``report.schedule.run_target`` logs ``pid target`` to
``$PROBECOMMIT_TARGET_PIDS``, and a process a target starts (a worker pool, a step set aside, the GRU's
training) is named by its nearest logged ancestor; the command's own process is ``main``. ``--stacks``: a
``py-spy dump`` each time a process's peak grows by ``--stacks-step`` MB from ``--stacks-from`` MB (where it
was when it grew). Printed: the largest processes, their targets and when they peaked. Linux only.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from target_memory import measure  # noqa: E402


def targets_of(result: dict, log: Path) -> dict[int, str]:
    """Per process seen, the target it runs (``main``: the command; ``target/child``: a process a target started)."""
    logged = {int(pid): name for pid, name, *_ in (line.split() for line in log.read_text().splitlines())} \
        if log.is_file() else {}
    parents = {int(k): v for k, v in result["parents"].items()}
    names = {}
    for pid in parents:
        cursor, hops = pid, 0
        while cursor and cursor not in logged and cursor != result["root_pid"]:
            cursor, hops = parents.get(cursor, 0), hops + 1
        base = logged.get(cursor, "main" if cursor == result["root_pid"] else "?")
        names[pid] = base if hops == 0 else f"{base}/child"
    return names


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", required=True, help="the reproduction's root")
    parser.add_argument("--json")
    parser.add_argument("--stacks", action="store_true")
    parser.add_argument("--stacks-from", type=int, default=400)
    parser.add_argument("--stacks-step", type=int, default=20)
    parser.add_argument("rest", nargs=argparse.REMAINDER, help="after --: more arguments of reproduce all")
    args = parser.parse_args()
    log = Path(args.out + ".pids")
    log.unlink(missing_ok=True)
    env = dict(os.environ, PROBECOMMIT_TARGET_PIDS=str(log))
    rest = [a for a in args.rest if a != "--"]
    argv = [sys.executable, "-m", "probecommit", "reproduce", "all", "-o", args.out, *rest]
    result = measure(argv, args, "reproduce all", lambda result: targets_of(result, log), env)
    sys.exit(result["rc"])


if __name__ == "__main__":
    main()
