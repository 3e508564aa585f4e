"""The invariant checks of one study's ``results.json`` and Parquet tables (identities and ranges).

Why: a few relations hold by construction (an interval contains its point, a paired
difference is the difference of its rows, a rate lies in [0, 1]); they are cheap and catch
an edit that recomputation does not reach (a number that is traced only). They are reported
as identities and ranges, never as "recomputed", and never make up the headline count.

Every check goes through ``Tally.check(kind, ok, message)``.
"""

from __future__ import annotations

import math
import re
from typing import Any, Iterator, Protocol

import numpy as np
import pandas as pd

#: Keys whose numbers are probabilities or rates.
RATE_WORDS = ("failure", "coverage", "escape", "success", "commit_rate", "fail", "realized", "predicted")
#: A key ending in a plural of those outcomes counts episodes (``held_failures``, ``escapes``): no rate.
COUNT_ENDINGS = ("failures", "escapes", "successes", "count")
#: A key starting with what it counts (``n_``, a sum, or the units counted: ``sessions_failing_at_least``,
#: ``positions_escape_is_beyond``) is a count, whatever outcome word follows.
COUNT_PREFIXES = ("n_", "sum_", "sessions_", "positions_")
TOLERANCE = 1e-9
#: Non-finite numbers a result may hold, by (study, key pattern with list indices as #): a gate
#: signal with no probability claim has no claimed failure.
DECLARED_NONFINITE = {("insertion", "results.gates.summary.#.claimed")}
#: Stored columns that may hold +inf, by (study, file, column pattern): a class surprise ``-log p`` of a reading the
#: belief gave probability 0 (``studies.explain.surprise_variants``; the AUC ranks it above every finite one).
DECLARED_INFINITE_COLUMNS = {("explain", "surprise_variants.parquet", r"class_k\d+"),
                             ("explain", "ex6_surprise_rows.parquet", r"class"),
                             ("explain", "ex7_fault_surprise.parquet", r"class"),
                             # W2's float32 weights: a tap contradicting every particle has predictive density 0
                             ("explain", "ex21_band_rows.parquet", r"surprise_(k1|final)")}
#: Stored columns that hold an episode's miss (metres, not a rate) under a name the rate rule would read as a rate,
#: by (study, file, column): the pyramidal-cone rows keep the elliptic cone's miss beside the re-executed one.
DECLARED_MISS_COLUMNS = {("explain", "ex4_cone_rows.parquet", "realized_elliptic")}


class Tally(Protocol):
    def check(self, kind: str, ok: bool, message: str) -> None: ...


def walk(node: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every (dotted key, value) of a JSON tree, list elements by index."""
    yield path, node
    if isinstance(node, dict):
        for key, value in node.items():
            yield from walk(value, f"{path}.{key}" if path else str(key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from walk(value, f"{path}.{i}")


def is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _triple(x: Any) -> bool:
    return isinstance(x, list) and len(x) == 3 and all(is_number(v) for v in x)


def _point(x: Any) -> float | None:
    return float(x) if is_number(x) else float(x[0]) if _triple(x) else None


def _is_rate(key: str) -> bool:
    word = re.split(r"\.", key)[-1].lower()
    if word.isdigit():
        word = key.split(".")[-2].lower()
    if word.startswith(COUNT_PREFIXES) or "escaped_" in word or word.endswith(COUNT_ENDINGS):  # a count or a sum
        return False
    if any(tag in word for tag in ("diff", "minus", "change", "optimism", "delta", "gap", "paired", "_s", "auc", "fix")):
        return False
    return any(w in word for w in RATE_WORDS)


def nonfinite(study: str, file: str, payload: Any, tally: Tally) -> None:
    """NaN or inf anywhere in a result fails unless declared in ``DECLARED_NONFINITE``."""
    for key, value in walk(payload):
        if isinstance(value, float) and not math.isfinite(value):
            pattern = re.sub(r"\.\d+(?=\.|$)", ".#", key)
            tally.check("range", (study, pattern) in DECLARED_NONFINITE,
                        f"{study}/{file}: {key} is {value} (not a declared non-finite value)")


def json_invariants(study: str, payload: dict[str, Any], tally: Tally) -> None:
    """Intervals, rates and identities of a results.json."""
    where = f"{study}/results.json"
    for key, value in walk(payload):
        if _triple(value):
            p, lo, hi = value
            if all(math.isfinite(v) for v in value):
                tally.check("range", lo - TOLERANCE <= p <= hi + TOLERANCE,
                            f"{where}: {key} = {p} lies outside its interval [{lo}, {hi}]")
        point = _point(value)
        if point is not None and math.isfinite(point) and _is_rate(key) and not isinstance(value, list):
            tally.check("range", -TOLERANCE <= point <= 1 + TOLERANCE, f"{where}: {key} = {point} is a rate outside [0, 1]")
        if isinstance(value, dict):
            _identities(where, key, value, tally)


def _identities(where: str, key: str, node: dict[str, Any], tally: Tally) -> None:
    pts = {k: _point(v) for k, v in node.items()}
    for k, v in pts.items():
        m = re.fullmatch(r"(.+)_minus_(.+)", k)
        if m and v is not None and pts.get(m.group(1)) is not None and pts.get(m.group(2)) is not None:
            expected = pts[m.group(1)] - pts[m.group(2)]
            tally.check("identity", abs(v - expected) < 1e-9,
                        f"{where}: {key}.{k} = {v} but {m.group(1)} - {m.group(2)} = {expected}")
    if all(pts.get(k) is not None for k in ("in_window", "episodes", "realized", "predicted", "optimism")):
        expected = 1.0 - pts["in_window"] / pts["episodes"]
        tally.check("identity", abs(pts["realized"] - expected) < 1e-9,
                    f"{where}: {key}.realized = {pts['realized']} but 1 - in_window / episodes = {expected}")
        tally.check("identity", abs(pts["optimism"] - (pts["realized"] - pts["predicted"])) < 1e-9,
                    f"{where}: {key}.optimism = {pts['optimism']} but realized - predicted = "
                    f"{pts['realized'] - pts['predicted']}")
    if "shift_vs_deployed_mm" in pts and pts.get("delta") is not None:
        expected = pts["delta"] + 1.2  # the deployed boundary is hg - r, r = 1.2 mm
        tally.check("identity", abs(pts["shift_vs_deployed_mm"] - expected) < 1e-9,
                    f"{where}: {key}.shift_vs_deployed_mm = {pts['shift_vs_deployed_mm']} but delta + r = {expected}")


def parquet_invariants(study: str, name: str, frame: pd.DataFrame, tally: Tally) -> None:
    """No infinity in a stored table, rates in [0, 1]."""
    where = f"{study}/{name}"
    tally.check("range", len(frame) > 0, f"{where}: no rows")
    for column in frame.columns:
        values = frame[column]
        if not pd.api.types.is_numeric_dtype(values) or pd.api.types.is_bool_dtype(values):
            continue
        arr = values.to_numpy(dtype=float, na_value=np.nan)
        declared = any(study == s and name == f and re.fullmatch(c, str(column)) for s, f, c in DECLARED_INFINITE_COLUMNS)
        inf = np.flatnonzero(np.isneginf(arr) if declared else np.isinf(arr))  # a declared column may hold +inf
        tally.check("range", not len(inf), f"{where}: column {column} = {arr[inf[0]] if len(inf) else ''} at row "
                                           f"{inf[0] if len(inf) else ''} is infinite")
        miss = column in ("realized", "predicted") or (study, name, column) in DECLARED_MISS_COLUMNS
        if _is_rate(column) and not miss:  # episode outcomes may be misses (m)
            bad = np.flatnonzero((arr < -TOLERANCE) | (arr > 1 + TOLERANCE))
            tally.check("range", not len(bad), f"{where}: {column} = {arr[bad[0]] if len(bad) else ''} at row "
                                               f"{bad[0] if len(bad) else ''} is a rate outside [0, 1]")
