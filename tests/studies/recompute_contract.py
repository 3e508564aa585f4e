"""The round trip every self-recomputing explain group must pass (``report.recompute.SELF_RECOMPUTING``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import pandas as pd


def assert_round_trip(tmp_path: Path, recompute: Callable[..., Any], group: str, stored: str, rows: pd.DataFrame,
                      keys: dict[str, Any]) -> None:
    """``rows`` stored as ``stored`` give back the group's published ``keys`` through ``recompute`` (verify),
    each sourced to that file; published keys without their rows are a problem."""
    published = {f"{group}.{k}": v for k, v in keys.items()}
    rows.to_parquet(tmp_path / stored)
    values, sources, problems = recompute(tmp_path, {group: keys})
    assert values == published and problems == [] and set(sources.values()) == {stored}
    (tmp_path / stored).unlink()
    assert recompute(tmp_path, {group: keys})[2]  # published keys without their rows: a problem
