"""Generate docs/record-schema.md from the schema module (a test keeps them in sync)."""

from __future__ import annotations

from probecommit.store.schema import AUDIT_REQUIRED, EPISODE_COLUMNS, INSTANCE_COLUMNS, PROBE_COLUMNS, markdown_table


def record_schema_markdown() -> str:
    return f"""# Record schema

The run directory's tables (Parquet, written with pyarrow; pandas or polars read them).
This page is generated from `src/probecommit/store/schema.py`; a test fails if they differ.

## episodes.parquet

One row per (instance, repeat, budget k, method). Budget 0 rows are the blind
baselines. Trajectories are nested: the budget-k row of a repeat used the first k
probes of that repeat's trajectory.

{markdown_table(EPISODE_COLUMNS)}

## Auditing your own robot's log

`probecommit audit LOG.csv` (or `.parquet`) needs only these columns:
{", ".join(f"`{c}`" for c in AUDIT_REQUIRED)}.
`covered` and `escaped` are derived from the intervals when absent; `status`
(`ok`/`failed`) excludes failed rows from every metric and counts them. Every
instance must have the same number of repeats at each budget (cluster coverage
needs all of them). `realized` is 0/1 failure for binary tasks, the miss otherwise;
`predicted` is the executor's modeled score of the action it took.

## probes.parquet

{markdown_table(PROBE_COLUMNS)}

## instances.parquet

{markdown_table(INSTANCE_COLUMNS)}

plus one `true_<latent>` column per latent (`true_x_hole`, `true_c` for insertion).

## engine_cache.parquet

Every deterministic engine answer of the run: `engine`, `query` (`tap_reading` or
`peg_depth`), `x_hole`, `c`, `arg` (tap position or aim, mm), `value` (mm). Replays
and calibration read it, so they never re-run a query the run already made.

## manifest.json

Written last; a directory without it is incomplete. Holds the package version,
engine versions, git commit, the sha256 of each table, engine-call counts,
timing (`engine_s`, `units_wall_s`) and failed-episode counts.
"""
