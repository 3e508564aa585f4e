"""Benchmark: the whole offline audit + calibration + gates, with side-by-side ratios.

Usage::

    python benchmarks/audit.py                 # synthetic 384-episode x 8-budget table
    python benchmarks/audit.py RUN               # also audits a run (engine time from its manifest)
    python benchmarks/audit.py RUN_CAL RUN_TEST  # ... and calibrates and gates RUN_TEST on RUN_CAL

Prints, measured in this one process:

- each stage's time and its share of the synthetic total;
- the vectorized cluster bootstrap against a loop over resamples (same draws);
- the event-sweep gate curve against first-passage evaluated per threshold;
- on runs: audit (+ calibrate + gates when two runs are given) against the
  engine wall time recorded in the run's ``manifest.json`` (``timing.engine_s``).
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from probecommit.audit.conformal import fixed_budget_thresholds, simultaneous_threshold
from probecommit.audit.gates import first_passage, gate_curve, gates_from_tables, trajectory_matrix
from probecommit.audit.io import read_episodes
from probecommit.audit.margin import distribution_free_margin, select_margin
from probecommit.audit.metrics import audit_table
from probecommit.report.audit_report import write_html_report
from probecommit.audit.stats import cluster_sums, resample_counts
from probecommit.audit.surprise import surprise_auc
from probecommit.audit.synthetic import synthetic_episodes

RESAMPLES = 2000


def timed(fn, *args, repeat: int = 3, **kwargs):
    """Best-of-``repeat`` wall time and the last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        best = min(best, time.perf_counter() - t0)
    return best, out


def loop_bootstrap(values, clusters, counts):
    """Reference: one resample at a time (what the vectorized version replaces)."""
    labels, sums, n = cluster_sums(values, clusters)
    out = np.empty(counts.shape[0])
    for b in range(counts.shape[0]):
        idx = np.repeat(np.arange(labels.size), counts[b])
        out[b] = sums[idx].sum() / n[idx].sum()
    return out


def brute_curve(signal, outcome):
    rows = []
    for tau in np.unique(signal[np.isfinite(signal)]):
        stop = first_passage(signal, tau)
        c = stop >= 0
        rows.append((tau, c.sum(), outcome[np.flatnonzero(c), stop[c]].mean() if c.any() else np.nan))
    return rows


def synthetic_benchmark() -> float:
    print("== synthetic: 96 instances x 4 repeats = 384 episodes, 8 budgets (3072 rows), "
          f"{RESAMPLES} bootstrap resamples ==")
    table = synthetic_episodes(96, 4, range(1, 9), n_particles=256, seed=0)
    cal = synthetic_episodes(96, 4, range(1, 9), n_particles=256, seed=1, prefix="cal")
    adjusted = table.assign(predicted=np.clip(table["predicted"] + 0.1, 0, 1))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "episodes.parquet"
        table.to_parquet(path)
        stages = {}
        stages["read + validate"], df = timed(read_episodes, path)
        stages["audit table (6 metrics x 8 budgets)"], audit = timed(audit_table, df, resamples=RESAMPLES)
        stages["surprise AUC (8 budgets)"], _ = timed(surprise_auc, df, resamples=RESAMPLES)
        stages["conformal thresholds (fixed + simultaneous)"], _ = timed(
            lambda: (fixed_budget_thresholds(cal), simultaneous_threshold(cal, range(1, 9))))
        # The margin search itself; each evaluate() here is a cheap stand-in for re-executing
        # the commit (the runner's cost, measured in the run benchmark below).
        stages["margin search (36 gammas) + distribution-free"], _ = timed(
            lambda: (select_margin(lambda g: cal.assign(predicted=cal["predicted"] + (1 - g)), exhaustive=True),
                     distribution_free_margin(cal)))
        stages["gates (4 signals, first passage)"], g = timed(gates_from_tables, df, adjusted)
        stages["HTML report"], _ = timed(write_html_report, Path(tmp) / "r.html", audit, gates=g, repeat=1)
    total = sum(stages.values())
    for name, t in stages.items():
        print(f"  {name:48s} {t * 1e3:8.1f} ms  {t / total:6.1%}")
    print(f"  {'total':48s} {total * 1e3:8.1f} ms  ({total / len(table) * 1e6:.1f} us per row)")

    counts = resample_counts(96, RESAMPLES, 0)
    values = df["realized"].to_numpy(float)
    clusters = df["instance_id"].to_numpy()
    labels, sums, n = cluster_sums(values, clusters)
    t_vec, vec = timed(lambda: (counts @ sums) / (counts @ n))
    t_loop, ref = timed(loop_bootstrap, values, clusters, counts, repeat=1)
    assert np.allclose(vec, ref)
    print(f"  cluster bootstrap: loop over resamples / vectorized = {t_loop / t_vec:8.1f}x "
          f"({t_loop * 1e3:.1f} ms vs {t_vec * 1e3:.2f} ms, identical draws)")
    _, _, sig = trajectory_matrix(df, "post_var")
    _, _, out = trajectory_matrix(df, "realized")
    t_sweep, curve = timed(gate_curve, sig, out)
    t_brute, ref = timed(brute_curve, sig, out, repeat=1)
    assert len(ref) == len(curve) and np.allclose([r[2] for r in ref], curve["failure"], equal_nan=True)
    print(f"  gate curve: per-threshold first passage / event sweep = {t_brute / t_sweep:8.1f}x "
          f"({len(curve)} thresholds; {t_brute * 1e3:.1f} ms vs {t_sweep * 1e3:.2f} ms)")
    return total


def engine_seconds(run: Path) -> float | None:
    manifest = json.loads((run / "manifest.json").read_text())
    return manifest.get("timing", {}).get("engine_s")


def run_benchmark(paths: list[Path], synthetic_total: float) -> None:
    from probecommit.audit.pipeline import audit
    from probecommit.runner.calibration import calibrate, gates

    test = paths[-1]
    print(f"== run: {test} ==")
    t_audit, res = timed(audit, test, repeat=1)
    rows = res.n_total
    print(f"  audit:      {t_audit:8.3f} s  ({rows} rows; synthetic total x{t_audit / synthetic_total:.2f})")
    spent = t_audit
    if len(paths) >= 2:
        t_cal, _ = timed(calibrate, paths[0], test, repeat=1)
        t_gates, _ = timed(gates, paths[0], test, repeat=1)
        print(f"  calibrate:  {t_cal:8.3f} s  (beliefs recomputed, commit re-executed per threshold and margin)")
        print(f"  gates:      {t_gates:8.3f} s")
        spent += t_cal + t_gates
    engine = engine_seconds(test)
    if engine:
        print(f"  engine wall time recorded in manifest: {engine:.3f} s")
        print(f"  audit{' + calibrate + gates' if len(paths) >= 2 else ''} / engine = {spent / engine:.3f}")
    else:
        print("  manifest has no timing.engine_s; no engine ratio")


def main(argv: list[str]) -> None:
    total = synthetic_benchmark()
    if argv:
        run_benchmark([Path(a) for a in argv], total)


if __name__ == "__main__":
    main(sys.argv[1:])
