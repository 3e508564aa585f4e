"""Column schemas of the run-directory tables (mirrored in docs/record-schema.md).

One module owns every table's columns and types, so the writer, the reader and the
audit's validation of a user's own log agree by construction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from probecommit.tasks.base import AnswerColumns


@dataclass(frozen=True)
class Column:
    """One column of a run-directory table.

    ``vector`` columns hold one component of a family's probe, observation or action:
    named ``u`` when the family's dimension is 1, else ``u_0 .. u_{p-1}``
    (:func:`component_names`).
    """

    name: str
    type: pa.DataType
    doc: str
    required_for_audit: bool = False
    vector: bool = False


def component_names(base: str, dim: int) -> list[str]:
    """Column names of a ``dim``-component quantity: ``[base]`` or ``[base_0, ..]``."""
    if dim < 1:
        raise ValueError(f"{base} needs at least one component, got {dim}")
    return [base] if dim == 1 else [f"{base}_{i}" for i in range(dim)]


def vector_columns(frame_columns, base: str) -> list[str]:
    """The component columns of ``base`` present in a table (``[base]`` or ``base_0..``)."""
    cols = list(frame_columns)
    if base in cols:
        return [base]
    found, i = [], 0
    while f"{base}_{i}" in cols:
        found.append(f"{base}_{i}")
        i += 1
    return found


INSTANCE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Stable instance identifier."),
    Column("split", pa.string(), "Instance set: development, A, B_cal, B_test, C, ..."),
    Column("instance_index", pa.int64(), "Index within the split (seeds derive from it)."),
    # Latent truth columns follow, one per latent name, prefixed 'true_'; then the
    # observed context, one column per context name, prefixed 'ctx_'.
)

PROBE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Instance identifier."),
    Column("repeat", pa.int64(), "Repeat index of this instance (0..R-1)."),
    Column("j", pa.int64(), "Probe index within the trajectory (1..K)."),
    Column("u", pa.float64(), "Probe (tap position, mm for insertion); u_0, u_1, ... for vector probes.", vector=True),
    Column("y", pa.float64(), "Observation (surface height, mm for insertion); y_0, y_1, ... for vector observations.", vector=True),
)

EPISODE_COLUMNS: tuple[Column, ...] = (
    Column("instance_id", pa.string(), "Instance identifier (the bootstrap cluster).", True),
    Column("repeat", pa.int64(), "Repeat index; cluster coverage needs every repeat.", True),
    Column("k", pa.int64(), "Probe budget: number of probes before the commit (0 = blind).", True),
    Column("method", pa.string(), "blind_bayes, blind_robust or probe_robust."),
    Column("variant", pa.string(), "Model variant that produced belief and action."),
    Column("action", pa.float64(), "Committed action (aim, mm); action_0, action_1, ... for vector actions.", vector=True),
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
    Column("belief_resets", pa.int64(), "Probes up to k after which every particle had zero likelihood and the weights were reset to uniform."),
    Column("status", pa.string(), "ok, or failed (the engine returned NaN or raised)."),
    Column("error", pa.string(), "Why the episode failed; empty when ok."),
)

#: The engine cache: every deterministic engine answer of a run, so replays never re-run one.
#: The instance's latent values follow ``query``, one column per latent name.
ENGINE_CACHE_COLUMNS: tuple[Column, ...] = (
    Column("engine", pa.string(), "Engine that answered (mujoco, pybullet, sapien, analytic)."),
    Column("query", pa.string(), "Named query (tap_reading, peg_depth, ...)."),
    # <latent> columns here, one per latent name of the family.
    Column("arg", pa.list_(pa.float64()), "The query's argument (tap position, aim, impulse, ...)."),
    Column("value", pa.list_(pa.float64()), "The engine's answer."),
)


def cache_columns(records: list[dict], latent_names: tuple[str, ...]) -> dict[str, list]:
    """Engine-cache rows (``Simulator.cache_records``) as columns keyed by the latent names, in
    table order (what :func:`cache_frame` makes a DataFrame of)."""
    columns: dict[str, list] = {"engine": [r["engine"] for r in records], "query": [r["query"] for r in records]}
    thetas = [tuple(r["theta"]) for r in records]
    for i, name in enumerate(latent_names):  # built column by column: a run may hold 10^5 answers
        columns[name] = [theta[i] if i < len(theta) else None for theta in thetas]
    columns["arg"] = [list(r["arg"]) for r in records]
    columns["value"] = [list(r["value"]) for r in records]
    return columns


def cache_frame(records: list[dict], latent_names: tuple[str, ...]):
    """Engine-cache rows (``Simulator.cache_records``) as a table keyed by the latent names."""
    import pandas as pd

    return pd.DataFrame(cache_columns(records, latent_names), columns=["engine", "query", *latent_names, "arg", "value"])


def answers_frame(answers: AnswerColumns, latent_names: tuple[str, ...]):
    """:func:`cache_frame` of answers given as columns (``CachedSimulator.answer_columns``): the
    same table, its columns made from the arrays (a replay keeps each chunk's engine answers)."""
    import pandas as pd

    if answers.thetas.shape[1] != len(latent_names):
        return cache_frame(list(answers), latent_names)
    columns = {"engine": list(answers.engines), "query": list(answers.queries),
               **{name: answers.thetas[:, i] for i, name in enumerate(latent_names)},
               "arg": answers.args.tolist(), "value": answers.values.tolist()}
    return pd.DataFrame(columns, columns=["engine", "query", *latent_names, "arg", "value"])


def cache_records(frame, latent_names: tuple[str, ...]) -> AnswerColumns:
    """Inverse of :func:`cache_frame`: the records a simulator's ``load_cache`` accepts, as columns
    (``tasks.base.AnswerColumns``: iterated, one dict a row).

    Whole columns are converted at once, and no list of per-row records is held beside the
    simulator's cache (a replay loads every answer of a run, often 10^4 rows or more), whose
    small objects would otherwise be interleaved with the freed records' in memory.

    Raises:
        ValueError: At the call, for a table without the family's columns.
    """
    if frame is None or not len(frame):
        return AnswerColumns([], [], np.empty((0, len(latent_names))), np.empty((0, 0)), np.empty((0, 0)))
    missing = [c for c in ("engine", "query", *latent_names, "arg", "value") if c not in frame.columns]
    if missing:
        raise ValueError(f"engine cache lacks column(s) {', '.join(missing)}; it was written for another task family")
    return AnswerColumns(frame["engine"].tolist(), frame["query"].tolist(), frame[list(latent_names)].to_numpy(float),
                         _float_rows(frame["arg"]), _float_rows(frame["value"]))


def float_matrix(items: list) -> np.ndarray | None:
    """Float vectors of one length as one ``[rows, length]`` array (one conversion for a whole
    column of an engine cache); None when their lengths differ."""
    try:
        return np.asarray(items, dtype=float).reshape(len(items), -1)
    except ValueError:  # rows of different lengths
        return None


def _float_rows(column) -> np.ndarray | list[np.ndarray]:
    """A column of float vectors as rows of float arrays (one ``float_matrix``, else row by row)."""
    items = column.tolist()
    matrix = float_matrix(items)
    return matrix if matrix is not None else [np.asarray(v, dtype=float).ravel() for v in items]


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
