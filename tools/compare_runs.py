"""Make a few quick runs (and a replay and a calibration) into a folder, or compare two such folders.

A refactoring that must not change any output is checked with it: run ``make OUT`` on the tree
before the change and on the tree after, then ``compare OLD NEW`` compares every Parquet table of
every run directory, table by table (exact equality, NaN equal to NaN), and every JSON answer.

    python tools/compare_runs.py make /tmp/before
    python tools/compare_runs.py compare /tmp/before /tmp/after [--tolerance 1e-9]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

#: (name, config, overrides): small runs covering binary and continuous loss, blind methods and contexts.
RUNS = [
    ("insertion", "demo", ["simulator.engine=analytic", "instances.count=6", "repeats=2",
                           "methods=[blind_bayes,blind_robust,probe_robust]", "belief.particles=256"]),
    ("insertion_test", "demo", ["simulator.engine=analytic", "instances.count=6", "repeats=2", "instances.seed=8",
                                "methods=[blind_bayes,blind_robust,probe_robust]", "belief.particles=256"]),
    ("push1d", "paper/push1d.yaml", ["repeats=2", "belief.particles=256", "blind_prior_samples=500"]),
    ("darts", "paper/darts.yaml", ["repeats=2", "belief.particles=256",
                                   "blind_prior_samples=500"]),
    ("grasp", "paper/grasp.yaml", ["repeats=2", "belief.particles=256",
                                   "blind_prior_samples=500"]),
]


def _config_path(name: str) -> str:
    from importlib import resources

    base = resources.files("probecommit") / "configs"
    return str(base / ("demo.yaml" if name == "demo" else name))


def make(out: Path) -> None:
    """The runs of :data:`RUNS`, a replay under the corrected insertion model and a calibration."""
    from probecommit.runner.calibration import calibrate
    from probecommit.runner.overrides import load_with_overrides, parse_override
    from probecommit.runner.replay import replay_run
    from probecommit.runner.study import run_study

    out.mkdir(parents=True, exist_ok=True)
    answers = {}
    for name, config, overrides in RUNS:
        cfg = load_with_overrides(_config_path(config), [parse_override(o) for o in overrides])
        run_study(cfg, out / name, threads=1)
    replay_run(out / "insertion", out / "insertion_corrected", {"model": {"boundary": "corrected"}})
    result = calibrate(out / "insertion", out / "insertion_test", alpha=0.2, resamples=50)
    answers["calibrate"] = repr(result)
    for name, value in vars(result).items():  # its tables compared in full, not only their repr
        if hasattr(value, "to_parquet"):
            value.to_parquet(out / f"calibrate_{name}.parquet")
    (out / "answers.json").write_text(json.dumps(answers, indent=1, sort_keys=True, default=str))


def compare(old: Path, new: Path, tolerance: float = 0.0) -> int:
    """Number of differing tables (printed); 0 when every table is equal."""
    import pandas as pd

    bad = 0
    tables = sorted(p.relative_to(old) for p in old.rglob("*.parquet"))
    for rel in tables:
        a = pd.read_parquet(old / rel)
        if not (new / rel).exists():
            print(f"missing {rel}")
            bad += 1
            continue
        b = pd.read_parquet(new / rel)
        try:
            if tolerance:
                pd.testing.assert_frame_equal(a, b, check_exact=False, rtol=tolerance, atol=tolerance)
            else:
                pd.testing.assert_frame_equal(a, b, check_exact=True)
            print(f"equal   {rel} ({len(a)} rows)")
        except AssertionError as exc:
            bad += 1
            print(f"DIFFER  {rel}: {str(exc).splitlines()[0:4]}")
    ja, jb = (json.loads((d / "answers.json").read_text()) for d in (old, new))
    if ja != jb:
        bad += 1
        print("DIFFER  answers.json")
    else:
        print("equal   answers.json")
    return bad


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(Path(sys.argv[2]))
    else:  # compare OLD NEW [--tolerance T]
        tol = float(sys.argv[sys.argv.index("--tolerance") + 1]) if "--tolerance" in sys.argv else 0.0
        sys.exit(1 if compare(Path(sys.argv[2]), Path(sys.argv[3]), tol) else 0)
