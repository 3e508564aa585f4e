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
from probecommit.store.yamlsafe import MAX_YAML_BYTES, MAX_YAML_DEPTH, MAX_YAML_NODES


def record_schema_markdown() -> str:
    """docs/record-schema.md: generated from the schema module, one function per part, so the
    page's column tables and limits come from the code they document and cannot drift from it."""
    return "".join(part() for part in (_introduction, _episode_table, _episode_rules, _session_log_rules,
                                       _config_manifest_output_rules, _other_tables))


def _introduction() -> str:
    """The title and the vector-column convention every table follows."""
    return f"""# Record schema

The run directory's tables (Parquet, written with pyarrow; pandas or polars read them).
This page is generated from `src/probecommit/store/schema.py`; a test fails if they differ.

**Vectors.** A family declares its probe, observation and action dimensions
(`probecommit tasks` lists them). A quantity with one component is one column (`u`,
`y`, `action`); one with `n > 1` components is `n` columns with a zero-based suffix
(`u_0`, `u_1`, ...; `action_0`, `action_1`), all float64. Insertion's tables therefore
keep their scalar columns; a 2-D push stores `action_0, action_1`.

"""


def _episode_table() -> str:
    """The episode table and the columns an audit of a robot's own log needs (the data contract users see first)."""
    return f"""## episodes.parquet

One row per (instance, repeat, budget k, method). Budget 0 rows are the blind
baselines. Trajectories are nested: the budget-k row of a repeat used the first k
probes of that repeat's trajectory.

{markdown_table(EPISODE_COLUMNS)}

## Auditing your own robot's log

`probecommit audit LOG.csv` (or `.parquet`) needs only these columns:
{", ".join(f"`{c}`" for c in AUDIT_REQUIRED)}.
`status` (`ok`/`failed`) excludes failed rows from every metric and counts them. Every
instance must have the same number of repeats at each budget (cluster coverage
needs all of them). `realized` is 0/1 failure for binary tasks, the miss otherwise;
`predicted` is the executor's modeled score of the action it took. The rules below
are checked on every row, whichever path reads it.

"""


def _episode_rules() -> str:
    """Why records are refused, not repaired, and the episode rows' rules (every audit path applies them)."""
    return f"""## Validation rule sets

One rule set per record kind, applied when a record is written and again on every path
that reads it. A record that breaks a rule is refused with one line naming the file, the
row or line and the field; nothing is dropped or changed silently.

### Episode rows (`audit.io.validate_episodes`)

Used by the CSV and Parquet audit, a run directory's `episodes.parquet`, the session-log
audit and replay (their rows go through it too), calibration and gates.

- Required columns present, each once; numbers numeric; `repeat` and `k` integers >= 0.
- On `ok` rows, every required number is finite and at most 1e12 in magnitude.
- `retained_lo <= retained_hi` and `hull_lo <= hull_hi`.
- Losses: `predicted >= 0` and `realized >= 0`. The loss kind is declared (`loss=` in
  the Python API) or inferred: binary when every `realized` is 0 or 1. For a binary
  table `realized` is 0 or 1 and `predicted` a failure fraction in [0, 1]. Undeclared,
  a `realized` column holding only 0 and 100 (a percent) is refused, as is a whole
  number other than 0/1 among 0/1 failures (say a 2).
- **Derived columns are recomputed, never trusted.** `covered` (z_true in the closed
  retained interval) and `escaped` (z_true outside the closed hull) are always computed
  from the intervals. A given column that contradicts them is *replaced by the
  recomputed value*, and the audit prints a warning with the number of rows and the
  first one (chosen over an error so that a log with a differently defined indicator
  still audits, with the documented definition).
- Structure: no duplicate episode; equal repeats per instance at each budget; every
  instance at every budget of its group.
- Intervals: a bootstrap over fewer than 2 clusters gives no interval (printed as `–`);
  under 10 clusters the audit warns that the intervals are unreliable.

"""


def _session_log_rules() -> str:
    """The session log's per-record rules and episode state machine (a log is checked on read as on write)."""
    return f"""### Session-log records (`robot.log.check_record`, `robot.session.Session._apply`)

One JSON object per line, standard JSON only (`NaN`, `Infinity` refused). Field rules per
type (numbers finite and at most 1e12 in magnitude, booleans never numbers):

| type | fields |
|---|---|
| `header` | `format` = `probecommit-session/1`, `config` a mapping (a valid study config) |
| `episode` | `episode` integer >= 0, `position` non-empty string, `taps` integer 0..64 |
| `observe` | `episode`, `u` and `y` non-empty lists of numbers; optional `j` integer >= 1 |
| `decide` | `episode`, `k`, `action` (list), `action_index` integer >= 0, `predicted` >= 0, `retained_lo <= retained_hi`, `hull_lo <= hull_hi`; optional `n_retained` >= 1 |
| `outcome` | `episode`; optional `entered` true/false/null, `notes` a mapping |
| `truth` | `position`, `theta` list of numbers (one per latent) |
| `rejected`, `note` | `call`/`reason`, `text` strings |

The episode state machine, enforced on read as the Session enforces it on write:
`episode` (numbered one past the last; the previous episode closed) -> `observe` x taps
(probe on the family's probe grid, reading of the model's dimension and physical range,
`j` in order) -> `decide` (after all taps, `k` = taps, the action equal to grid action
`action_index`, a binary task's `predicted` in [0, 1]) -> `outcome`. A header naming
another family therefore fails on the first probe or action off that family's grid.

Writing is all or nothing: each record is checked, then written with one `os.write` of
its full bytes on an unbuffered descriptor and fsync'd; a failed or short write is
truncated back and raised (naming the log), so a record that failed is never written
later. The writer's lock is an advisory lock on the log file itself (deleting
`session.jsonl.lock`, which only names the holder, does not let a second writer in);
a symlink at the log or the lock note is refused. A replay reproduces a decision only
when the action, `predicted`, the retained interval and the hull all match.

"""


def _config_manifest_output_rules() -> str:
    """The rules for configs, manifests and output files (the inputs and outputs beside the tables)."""
    return f"""### Configs (`runner.config.load_config`, `store.yamlsafe.load_yaml`)

Every YAML the package reads (a config file, a `--set` value, a run's `config.yaml`,
a protocol) is read by one loader: at most {MAX_YAML_BYTES:,} characters, at most
{MAX_YAML_NODES:,} nodes after alias and merge-key expansion (counted before anything
is built), nesting at most {MAX_YAML_DEPTH} deep, no recursive alias, safe tags only
(`!!python/...` refused), no duplicate key. Then the pydantic model: unknown fields,
NaN, infinity and booleans-as-numbers are errors. A family's ranges apply to fixed
`instances.truths` (their bounding box) and `instances.contexts` exactly as to a sampled
truth box; truths x contexts is at most 100,000 instances. Before a run starts, the memory
of the units held at once (workers, or twice the threads) and of the final tables is
checked against the smaller of the host's available memory and the container's (cgroup)
headroom, and the episode rows are bounded (50,000,000).

### Manifests (`store.manifest_rules`)

A JSON object whose `sha256` is a non-empty mapping of relative file name to 64 hex
digits. A reader refuses a run directory unless the manifest lists every file it reads
(`episodes.parquet` and `config.yaml` for the audit; every table and the config for a
replay) and each listed file matches; a folder counts as a run directory when it holds
any run file besides `episodes.parquet` (removing `config.yaml` or `shards/` does not
make a run a user's folder). An unreadable or invalid manifest or results file is named.

### Output (`store.safefile`, `cli.common`)

Every user-visible file is written by `store.safefile.write_bytes`: a symlink at the
destination is refused (never followed), the bytes go to a fresh temporary file beside
it and are renamed over it. A default output folder inside a run (`calibration/`,
`gates/`, `LOG-audit/`) that is a symlink is refused. All text from data and paths
reaches the terminal through one console that interprets no markup and no emoji codes
and shows every control character as `?`.

"""


def _other_tables() -> str:
    """The probe, instance and engine-answer tables and the manifest."""
    return f"""## probes.parquet

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
