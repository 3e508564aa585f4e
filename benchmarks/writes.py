"""Durable writes of a run's units: group-committed batches against a file per table per unit.

The units' tables are those of a real study (analytic insertion, ``--instances`` x 4 repeats,
k = 1..8, N = 1024, units of 4 instances), computed once. Two arms then store the same units
durably, in turn for ``--rounds`` rounds, into fresh folders beside each other:

* ``batches``: what ``run_study`` does now (``RunDir.add_unit``, batches of up to 256 units or
  2 s: one temporary file, one fsync, one rename, one fsync of ``shards/`` per batch);
* ``per-unit files``: what it did before (each unit's four tables as Parquet and its stats as
  JSON, five files each written to a temporary file, fsynced and renamed).

Medians and the ratio are printed, with the load average (fsync time depends on the disk and
on what else writes to it).

    python benchmarks/writes.py [--instances 480] [--rounds 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from probecommit.runner.config import parse_config
from probecommit.runner.study import _groups, compute_units, unit_names
from probecommit.runner.build import build_model
from probecommit.runner.instances import draw_instances
from probecommit.store.rundir import RunDir, atomic_write_bytes


def units_of(instances: int) -> list[tuple]:
    config = parse_config({
        "name": "writes", "seed": 7, "repeats": 4, "instances": {"split": "w", "count": instances, "seed": 1},
        "probes": {"schedule": "random", "budget": 8}, "belief": {"particles": 1024},
        "simulator": {"engine": "analytic"}, "methods": ["probe_robust"], "unit_instances": 4,
    })
    drawn = draw_instances(config, build_model(config))
    todo = unit_names(len(drawn), config.unit_instances)
    out = []
    for job in _groups(config.model_dump(mode="json"), drawn, todo, config.repeats, 1):
        out.extend(compute_units(*job))
    return out


def batches(units: list[tuple], folder: Path) -> None:
    run = RunDir(folder)
    run.shards.mkdir(parents=True)
    for unit, tables, stats in units:
        run.add_unit(unit, tables, stats)
    run.flush()


def per_unit_files(units: list[tuple], folder: Path) -> None:
    shards = folder / "shards"
    shards.mkdir(parents=True)
    for unit, tables, stats in units:
        for name in ("instances", "probes", "engine_cache"):
            atomic_write_bytes(shards / f"{unit}.{name}.parquet", _parquet(tables[name]))
        atomic_write_bytes(shards / f"{unit}.stats.json", json.dumps(stats).encode())
        atomic_write_bytes(shards / f"{unit}.episodes.parquet", _parquet(tables["episodes"]))


def _parquet(table: pa.Table) -> bytes:
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=480)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    units = units_of(args.instances)
    arms = {"batches": batches, "per-unit files": per_unit_files}
    times: dict[str, list[float]] = {name: [] for name in arms}
    with tempfile.TemporaryDirectory(dir=os.environ.get("TMPDIR")) as tmp:
        n = 0
        for _ in range(args.rounds + 1):  # the first round warms up
            for name, arm in arms.items():
                n += 1
                t0 = time.perf_counter()
                arm(units, Path(tmp) / f"{n}")
                if _ > 0:
                    times[name].append(time.perf_counter() - t0)
    med = {name: statistics.median(values) for name, values in times.items()}
    print(f"storing {len(units)} units durably (median of {args.rounds} rounds; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")
    for name in arms:
        print(f"  {name + ':':16s} {med[name]:6.3f} s")
    print(f"  per-unit files / batches = {med['per-unit files'] / med['batches']:.1f}x")


if __name__ == "__main__":
    sys.exit(main())
