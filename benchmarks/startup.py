"""Start-up as the user gets it: `probecommit --help` and a 4-episode run, timed as processes.

Each arm is a fresh process, run in turn with the others for ``--runs`` rounds (after one
warm-up round that fills the OS file cache); the medians are printed with the targets and,
measured side by side, the ratios to the interpreter's own start-up (``python -c pass``) and
to ``python -c "import numpy"``, wall and CPU time. The package's bytecode is compiled first and
the processes may load it, as from a user's install (``as_user.py``). With ``--against REF`` the same commands of a git ref
(checked out beside this tree) take turns with this tree's, and the ratios ref / this tree
are printed too.

    python benchmarks/startup.py [--runs 9] [--against REF]

Targets (issue 42, on an idle 2-core machine): ``--help`` <= 0.3 s, the 4-episode run <= 1 s.
"""

from __future__ import annotations

import argparse
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
FOUR = """name: four
seed: 1
repeats: 1
instances: {split: test, count: 4, seed: 1}
probes: {budget: 8}
belief: {particles: 1024}
simulator: {engine: analytic}
"""
TARGETS = {"help": 0.3, "run4": 1.0}


def timed(cmd: list[str], env: dict[str, str], before=None) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of one process."""
    if before is not None:
        before()
    t0, c0 = time.perf_counter(), children_cpu()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t0, children_cpu() - c0


def arms_of(src: Path, tag: str, tmp: Path) -> dict[str, tuple]:
    """The two commands of one tree, each a fresh process (the run into a fresh directory)."""
    env = user_env(src, COLUMNS="120")
    config = tmp / "four.yaml"
    out = tmp / f"run-{tag}"
    command = [sys.executable, "-m", "probecommit"]
    return {
        f"help{tag}": (command + ["--help"], env, None),
        f"run4{tag}": (command + ["run", str(config), "--out", str(out)], env,
                       lambda: shutil.rmtree(out, ignore_errors=True)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--against", help="a git ref whose commands take turns with this tree's")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        (tmp / "four.yaml").write_text(FOUR)
        plain_env = user_env(ROOT / "src")
        compile_tree(ROOT / "src")
        arms = {
            "python": ([sys.executable, "-c", "pass"], plain_env, None),
            "numpy": ([sys.executable, "-c", "import numpy"], plain_env, None),
            **arms_of(ROOT / "src", "", tmp),
        }
        with (baseline_tree(args.against, tmp / "ref") if args.against else _nothing()) as ref:
            if ref is not None:
                compile_tree(ref / "src")
                arms.update(arms_of(ref / "src", "@ref", tmp))
            times: dict[str, list[tuple[float, float]]] = {name: [] for name in arms}
            for name, arm in arms.items():  # warm-up: the file cache, compiled bytecode
                timed(*arm)
            load = []
            for _ in range(args.runs):
                load.append(os.getloadavg()[0])
                for name, arm in arms.items():
                    times[name].append(timed(*arm))
    med = {name: statistics.median(wall for wall, _ in values) for name, values in times.items()}
    cpu = {name: statistics.median(c for _, c in values) for name, values in times.items()}
    print(f"start-up as processes: median of {args.runs} interleaved runs (load average "
          f"{min(load):.1f}-{max(load):.1f} on {os.cpu_count()} CPUs; targets are for an idle machine)")
    for name, label in (("python", "python -c pass"), ("numpy", "python -c 'import numpy'"),
                        ("help", "probecommit --help"), ("run4", "probecommit run (4 analytic episodes)")):
        target = f"   target <= {TARGETS[name]:.1f} s: {'met' if med[name] <= TARGETS[name] else 'missed'}" \
            if name in TARGETS else ""
        ratios = f"   {med[name] / med['python']:5.1f}x python, {med[name] / med['numpy']:4.1f}x numpy" \
            if name not in ("python",) else ""
        print(f"  {label:44s} {med[name]:6.3f} s (CPU {cpu[name]:5.3f} s){ratios}{target}")
        if f"{name}@ref" in med:
            print(f"  {label + ' at ' + args.against:44s} {med[name + '@ref']:6.3f} s (CPU {cpu[name + '@ref']:5.3f} s)"
                  f"   ref / this tree = {med[name + '@ref'] / med[name]:.2f} (CPU {cpu[name + '@ref'] / cpu[name]:.2f})")


class _nothing:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


if __name__ == "__main__":
    main()
