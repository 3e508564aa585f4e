"""Column schemas of the run-directory tables (mirrored in docs/record-schema.md).

One module owns every table's columns and types, so the writer, the reader and the
audit's validation of a user's own log agree by construction.
"""

from __future__ import annotations

from dataclasses import dataclass

import pyarrow as pa


@dataclass(frozen=True)
class Column:
    name: str
    type: pa.DataType
    doc: str
    required_for_audit: bool = False


INSTANCE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Stable instance identifier."),
    Column("split", pa.string(), "Instance set: development, A, B_cal, B_test, C, ..."),
    Column("instance_index", pa.int64(), "Index within the split (seeds derive from it)."),
    # Latent truth columns follow, one per latent name, prefixed 'true_'.
)

PROBE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Instance identifier."),
    Column("repeat", pa.int64(), "Repeat index of this instance (0..R-1)."),
    Column("j", pa.int64(), "Probe index within the trajectory (1..K)."),
    Column("u", pa.float64(), "Probe (tap position, mm for insertion)."),
    Column("y", pa.float64(), "Observation (surface height, mm for insertion)."),
)

EPISODE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Instance identifier (the bootstrap cluster).", True),
    Column("repeat", pa.int64(), "Repeat index; cluster coverage needs every repeat.", True),
    Column("k", pa.int64(), "Probe budget: number of probes before the commit (0 = blind).", True),
    Column("method", pa.string(), "blind_bayes, blind_robust or probe_robust."),
    Column("variant", pa.string(), "Model variant that produced belief and action."),
    Column("action", pa.float64(), "Committed action (aim, mm)."),
    Column("predicted", pa.float64(), "Modeled score of the chosen action (scenario failure fraction or max miss).", True),
    Column("realized", pa.float64(), "Realized outcome: failure 0/1 (binary tasks) or miss.", True),
    Column("z_true", pa.float64(), "True decision coordinate (ground truth, audit only).", True),
    Column("retained_lo", pa.float64(), "Lower end of the retained set's decision-coordinate interval.", True),
    Column("retained_hi", pa.float64(), "Upper end of the retained set's decision-coordinate interval.", True),
    Column("hull_lo", pa.float64(), "Lower end of the full particle hull in the decision coordinate.", True),
    Column("hull_hi", pa.float64(), "Upper end of the full particle hull in the decision coordinate.", True),
    Column("covered", pa.bool_(), "z_true within [retained_lo, retained_hi]."),
    Column("escaped", pa.bool_(), "z_true outside [hull_lo, hull_hi] (support escape)."),
    Column("score_s", pa.float64(), "Coverage score s: mass of the shortest prefix covering the truth; 1 + d/D past the hull."),
    Column("post_var", pa.float64(), "Posterior variance of the decision coordinate."),
    Column("max_surprise", pa.float64(), "Max over probes seen of -log predictive density before assimilation."),
    Column("n_retained", pa.int64(), "Number of retained particles (scenarios)."),
    Column("status", pa.string(), "ok, or failed (the engine returned NaN or raised)."),
    Column("error", pa.string(), "Why the episode failed; empty when ok."),
)

#: Columns a user's own log must provide for ``probecommit audit``.
AUDIT_REQUIRED = tuple(c.name for c in EPISODE_COLUMNS if c.required_for_audit)


def checked_frame(table, required: tuple[str, ...], source: str, error: type[Exception], needs: str):
    """A copy of ``table`` with stripped column names, after the checks every reader makes.

    Raises ``error`` with one line for missing required columns (``needs`` names the
    kind of table), a column given twice, or no rows.
    """
    df = table.copy()
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise error(f"{source}: missing required column(s) {', '.join(missing)}; {needs} needs {', '.join(required)}")
    duplicated = df.columns[df.columns.duplicated()]
    if len(duplicated):
        raise error(f"{source}: column '{duplicated[0]}' appears more than once")
    if len(df) == 0:
        raise error(f"{source}: the table has no rows")
    return df.reset_index(drop=True)


def arrow_schema(columns: tuple[Column, ...]) -> pa.Schema:
    return pa.schema([pa.field(c.name, c.type) for c in columns])


def markdown_table(columns: tuple[Column, ...]) -> str:
    """The schema as a Markdown table (docs/record-schema.md is generated from this)."""
    lines = ["| column | type | required by audit | meaning |", "|---|---|---|---|"]
    for c in columns:
        lines.append(f"| `{c.name}` | {c.type} | {'yes' if c.required_for_audit else ''} | {c.doc} |")
    return "\n".join(lines)
