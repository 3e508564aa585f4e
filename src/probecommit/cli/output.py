"""How the CLI prints result tables and writes them as CSV (shared by every command group)."""

from __future__ import annotations

import math
from pathlib import Path

from probecommit.cli.common import console
from probecommit.store.safefile import write_bytes


def number(value, signed: bool = False, missing: str = "–") -> str:
    """A result number as every command prints it: three decimals (a sign with ``signed``);
    ``missing`` for None and NaN (a metric the data leave undefined); other text as it is."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return missing if value is None else str(value)
    if math.isnan(v):
        return missing
    return f"{v:+.3f}" if signed else f"{v:.3f}"


def print_table(table) -> None:
    """Print a table of intervals whole: in a pipe or a CI log (no terminal) the width is not
    capped at 80 columns, so an interval is never cut or wrapped mid-number."""
    if console.is_terminal:
        console.print(table)
        return
    saved = console.width
    console.width = 400  # the table takes only the width it needs
    try:
        console.print(table)
    finally:
        console.width = saved


def write_csv(frame, path: Path, paper_names: bool = False) -> None:
    """CSV for spreadsheets: text cells that a spreadsheet would run as a formula
    (``=``, ``+``, ``-``, ``@``, tab, CR first) are prefixed with a quote (OWASP CSV injection).
    ``paper_names``: the header in the paper's words (``realized_R_k``, ``optimism_e_k``, ...)."""
    import pandas as pd

    out = frame.copy()
    if paper_names:
        from probecommit.report.vocabulary import csv_name

        out = out.rename(columns=csv_name)
    for col in out.columns:
        if pd.api.types.is_object_dtype(out[col]) or pd.api.types.is_string_dtype(out[col]):
            out[col] = out[col].map(lambda v: "'" + v if isinstance(v, str) and v[:1] in ("=", "+", "-", "@", "\t", "\r") else v)
    write_bytes(path, out.to_csv(index=False).encode())
