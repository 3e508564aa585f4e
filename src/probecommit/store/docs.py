"""Generate docs/record-schema.md from the schema module (a test keeps them in sync)."""

from __future__ import annotations

from probecommit.store.schema import (
    AUDIT_REQUIRED,
    ENGINE_CACHE_COLUMNS,
    EPISODE_COLUMNS,
    INSTANCE_COLUMNS,
    PROBE_COLUMNS,
    markdown_table,
)


def record_schema_markdown() -> str:
    return f"""# Record schema

The run directory's tables (Parquet, written with pyarrow; pandas or polars read them).
This page is generated from `src/probecommit/store/schema.py`; a test fails if they differ.

**Vectors.** A family declares its probe, observation and action dimensions
(`probecommit tasks` lists them). A quantity with one component is one column (`u`,
`y`, `action`); one with `n > 1` components is `n` columns with a zero-based suffix
(`u_0`, `u_1`, ...; `action_0`, `action_1`), all float64. Insertion's tables therefore
keep their scalar columns; a 2-D push stores `action_0, action_1`.

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

plus one `true_<latent>` column per latent (`true_x_hole`, `true_c` for insertion)
and one `ctx_<name>` column per observed context coordinate of the family (a target
position, say: `ctx_target_x`, `ctx_target_y`); an instance is (truth, context).

## engine_cache.parquet

Every deterministic engine answer of the run, one schema for every family:

{markdown_table(ENGINE_CACHE_COLUMNS)}

with one float64 column per latent name of the family between `query` and `arg`
(`x_hole`, `c` for insertion). `arg` and `value` are lists, so a query may take or
return a vector (a 2-D impulse, a 2-D rest position). Replays and calibration read
it, so they never re-run a query the run already made.

## manifest.json

Written last; a directory without it is incomplete. Holds the package version,
engine versions, git commit, the sha256 of each table, engine-call counts,
timing (`engine_s`, `units_wall_s`) and failed-episode counts.
"""
