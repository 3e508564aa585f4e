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


def assert_bootstrapped_round_trip(tmp_path: Path, module: Any, rows: pd.DataFrame, keys: dict[str, Any],
                                   boot: dict[str, int]) -> None:
    """``rows`` stored as ``module.STORED`` give back ``module.GROUP``'s published ``keys`` through ``module.recompute``
    (a ``report.recompute.BOOTSTRAPPED`` module), each sourced to that file, NaN for NaN."""
    import math

    rows.to_parquet(tmp_path / module.STORED)
    got = module.recompute(tmp_path, {module.GROUP: keys}, boot)
    assert set(got) == {f"{module.GROUP}.{k}" for k in keys}
    for key, (v, source) in got.items():
        ref = keys[key.split(".", 1)[1]]
        assert source == module.STORED
        assert (isinstance(v, float) and math.isnan(v) and math.isnan(ref)) or v == ref, key


def assert_stored_summary_round_trip(tmp_path: Path, module: Any, rows: pd.DataFrame) -> None:
    """``module``'s group is one ``summary(rows)`` of its stored table (``report.recompute.STORED_SUMMARIES``):
    ``rows`` stored as ``module.STORED`` give back every published key through verify's ``_stored_summaries``."""
    from probecommit.report import recompute

    assert (module.GROUP, module.STORED, module.__name__.rsplit(".", 1)[1]) in recompute.STORED_SUMMARIES
    keys = module.summary(rows)
    rows.to_parquet(tmp_path / module.STORED)
    out = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {module.GROUP: keys}, out)
    assert {k: v for k, v in out.values.items() if k.startswith(module.GROUP + ".")} \
        == {f"{module.GROUP}.{k}": v for k, v in keys.items()}
