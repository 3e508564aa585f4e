"""The paper's words for the audit's quantities, in one place.

HTML reports, the CSV column headers of audit outputs and figure labels take their
names from here, so the same quantity is never "failure" in one output, "R_k" in a
second and "real" in a third. Two spellings each: ``HTML`` (Unicode subscripts, for
pages and figure text) and ``CSV`` (ASCII, no spaces, for a spreadsheet's header row).
The CLI's tables (owned by the conventions work) can read the same constants.
"""

from __future__ import annotations

#: column name in the episode/audit tables -> the paper's name (HTML and figures).
HTML = {
    "k": "budget k",
    "taps": "taps k",
    "aim_error": "aim error (mm)",
    "in_window": "in window",
    "covered": "covered",
    "entered": "entered",
    "realized": "realized Rₖ",
    "predicted": "predicted R̂ₖ",
    "optimism": "optimism eₖ",
    "coverage": "coverage",
    "cluster_coverage": "cluster coverage",
    "escape": "support escape",
    "n_episodes": "episodes",
    "n_instances": "instances",
    "n_clusters": "clusters",
    "n_repeats": "repeats",
    "n_failed": "failed",
    "n_escaped": "escaped",
    "n_covered": "not escaped",
    "auc": "rank AUC",
    "method": "method",
    "variant": "model variant",
    "threshold": "threshold tₖ",
    "posterior_variance": "posterior variance",
    "signal": "signal",
    "claimed": "predicted R̂ₖ at commit",
    "commit_rate": "commit rate",
}

#: The same names for a CSV header row (ASCII; what a spreadsheet shows).
CSV = {
    "k": "budget_k",
    "realized": "realized_R_k",
    "predicted": "predicted_Rhat_k",
    "optimism": "optimism_e_k",
    "coverage": "coverage",
    "cluster_coverage": "cluster_coverage",
    "escape": "support_escape",
}

#: Figure axis labels (with units where there are any).
AXIS = {
    "k": "budget k (probes)",
    "realized": "realized Rₖ",
    "predicted": "predicted R̂ₖ",
    "optimism": "optimism eₖ = Rₖ − R̂ₖ",
    "coverage": "coverage",
    "cluster_coverage": "cluster coverage",
    "escape": "support escape",
}

#: Columns a reader needs first; an audit table keeps these at its left edge.
KEY_COLUMNS = ("k", "taps", "method", "variant", "coverage", "cluster_coverage", "escape", "realized", "predicted", "optimism")

#: Fewer clusters than this: an interval is flagged as resting on too few clusters.
MIN_CLUSTERS = 10


def html_name(column: str) -> str:
    """The paper's name of a column for HTML and figures; unknown columns lose their underscores."""
    if column in HTML:
        return HTML[column]
    for suffix, word in (("_lo", " (low)"), ("_hi", " (high)")):
        if column.endswith(suffix) and column[: -len(suffix)] in HTML:
            return HTML[column[: -len(suffix)]] + word
    return column.replace("_", " ")


def csv_name(column: str) -> str:
    """The paper's name of a column for a CSV header (``optimism_lo`` -> ``optimism_e_k_lo``)."""
    if column in CSV:
        return CSV[column]
    for suffix in ("_lo", "_hi"):
        if column.endswith(suffix) and column[: -len(suffix)] in CSV:
            return CSV[column[: -len(suffix)]] + suffix
    return column


#: Method names as the paper writes them.
METHODS = {"probe_robust": "Probe-Robust", "blind_bayes": "Blind-Bayes", "blind_robust": "Blind-Robust"}


def value_name(value: object) -> str:
    """A cell value or legend entry as a reader says it (method names the paper's way, no underscores)."""
    text = str(value)
    return METHODS.get(text, text.replace("_", " "))


def default_output(path, kind: str = "audit"):
    """Where an audit of ``path`` writes when no ``-o`` is given: ``<input>-<kind>/`` beside the input.

    One rule for every input (a run directory, a CSV or Parquet log, a robot session log or
    its directory): ``runs/x`` -> ``runs/x-audit/``, ``log.csv`` -> ``log-audit/``.
    """
    from pathlib import Path

    path = Path(path)
    base = path.name if path.is_dir() else path.stem
    return path.with_name(f"{base}-{kind}")
