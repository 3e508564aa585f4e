"""Where `probecommit run`'s CPU goes on the end-to-end config (issue 42, target 1): CPU seconds of
the imports and of each coarse piece of ``run_study`` (rollouts, filter updates, commits, belief
summaries, unit tables, writes, finalize), one thread, in this process. With ``--command`` the
command itself runs in this process (``probecommit.cli.app.main``: its heap settings, preflight,
progress bar, summary table and exit), and the rest of its CPU is shown too: the interpreter's
start, the command's imports and its own steps.

Wrappers on a few coarse calls (hundreds of calls in all), not a profiler: a profiler's per-call
cost inflates the pieces made of many small calls (the rollout's per-tap engine calls) several
fold. Nested pieces are indented under the piece that calls them; a piece's time includes theirs.

    python benchmarks/run_parts.py [--instances 480] [--repeats 4] [--command]
"""

from __future__ import annotations

import argparse
import atexit
import collections
import contextlib
import functools
import io
import shutil
import sys
import tempfile
import time
from pathlib import Path

T0 = time.process_time()  # the interpreter's start (site, this script's own imports)
import probecommit.cli.app as cli_app  # noqa: E402
import probecommit.core.belief as core_belief  # noqa: E402
import probecommit.core.executors as core_executors  # noqa: E402
import probecommit.runner.inference as inference  # noqa: E402
import probecommit.runner.overrides as overrides  # noqa: E402
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
#: The command's own steps around ``run_study`` (``--command``).
COMMAND_PIECES = [
    (overrides, "load_with_overrides", "config read and validated"),
    (study.RunParts, "build", "model, filter and executors built"),
    (study, "preflight", "preflight (simulator, instances, memory checks)"),
    (cli_app, "progress_bar", "progress bar made"),
    (cli_app, "print_budget_table", "summary table printed"),
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
    ap.add_argument("--command", action="store_true", help="run `probecommit run --threads 1` itself, in this process")
    args = ap.parse_args()
    for owner, name, label in PIECES + COMMAND_PIECES + [(study, "run_study", "run_study")]:
        _timed(owner, name, label)
    for cls in vars(core_executors).values():
        if isinstance(cls, type) and "decide" in vars(cls):
            _timed(cls, "decide", "  executors decide")
    tmp = Path(tempfile.mkdtemp())
    path = tmp / "e2e.yaml"
    path.write_text(CONFIG.format(instances=args.instances, repeats=args.repeats, unit_instances=4))
    print(f"CPU seconds, {args.instances * args.repeats} episodes, one thread:")
    print(f"  {'interpreter start':54s} {T0:6.3f}")
    print(f"  {'imports (the command, runner, store, core)':54s} {IMPORTS:6.3f}")
    if not args.command:
        reuse_freed_arrays()  # as the command does
        study.run_study(load_config(path), tmp / "run", threads=1)
        _print_pieces()
        shutil.rmtree(tmp, ignore_errors=True)
        return
    atexit.register(_print_pieces, command=True, tmp=tmp)  # the command ends the process (exit_process)
    sys.argv = ["probecommit", "run", str(path), "--out", str(tmp / "run"), "--threads", "1"]
    with contextlib.redirect_stdout(io.StringIO()):
        cli_app.main()


def _print_pieces(command: bool = False, tmp: Path | None = None) -> None:
    """The pieces' CPU; for the command, its own steps and what is left (typer's dispatch, exit)."""
    out = sys.__stdout__  # the command's own output is captured (and the process ends in exit_process)
    labels = [label for _, _, label in COMMAND_PIECES if CPU[label]] if command else []
    for label in labels:
        print(f"  {label:54s} {CPU[label]:6.3f}", file=out)
    print(f"  {'run_study':54s} {CPU['run_study']:6.3f}", file=out)
    for label in [p[2] for p in PIECES[:6]] + ["  executors decide"] + [p[2] for p in PIECES[6:]]:
        print(f"    {label:52s} {CPU[label]:6.3f}", file=out)
    if command:
        total = time.process_time()
        rest = total - T0 - IMPORTS - CPU["run_study"] - sum(CPU[label] for label in labels)
        print(f"  {'the rest (typer dispatch, lazy imports, exit)':54s} {rest:6.3f}", file=out)
        print(f"  {'the process in all':54s} {total:6.3f}", file=out)
        shutil.rmtree(tmp, ignore_errors=True)
    out.flush()


if __name__ == "__main__":
    main()
