"""Read and validate episode tables: our run directories and a user's own log.

The audit accepts any table with the documented episode columns
(``store.schema.EPISODE_COLUMNS``), a real robot's CSV log included, and refuses
a malformed one with ONE message that names the problem, the column and the first
offending row. Row numbers are 0-based data rows; for CSV input the file line
(header = line 1) is given too, so a user can jump to it in an editor.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd
import pyarrow as pa

from probecommit.store.schema import AUDIT_REQUIRED, EPISODE_COLUMNS, checked_frame
from probecommit.errors import UserError

#: Columns that identify one episode within a (method, variant) group.
KEY_COLUMNS = ("instance_id", "repeat", "k")
#: Optional grouping columns; metrics are reported per group when present.
GROUP_COLUMNS = ("method", "variant")
#: Required float columns that may not be NaN on an ok episode.
FINITE_REQUIRED = tuple(c for c in AUDIT_REQUIRED if c not in ("instance_id", "repeat", "k"))

_TYPES = {c.name: c.type for c in EPISODE_COLUMNS}
#: Largest magnitude of a required float (a larger one is a unit or parse error, and its
#: differences would overflow to inf).
MAX_MAGNITUDE = 1e12
#: Loss kinds an episode table may declare.
LOSS_KINDS = ("binary", "continuous")
_OK_STATUS = ("ok", "failed")


class EpisodeTableError(UserError, ValueError):
    """An episode table that the audit cannot use; the message names the problem."""


def _where(row: int, csv: bool) -> str:
    return f"row {row} (CSV line {row + 2})" if csv else f"row {row}"


#: Files whose presence makes a folder a probecommit run directory (any one of them).
RUN_MARKERS = ("config.yaml", "manifest.json", "shards", "instances.parquet", "probes.parquet")


def _check_intact(run_dir: Path) -> None:
    """A run directory is audited only if complete and unchanged since its manifest.

    A folder is a run directory when it holds any run file besides ``episodes.parquet``
    (removing some of them does not make a run a user's folder). Its manifest must list
    ``episodes.parquet`` and the config, and every listed file must match its digest.
    """
    from probecommit.store.manifest_rules import ManifestError, verify_files

    if not any((run_dir / name).exists() for name in RUN_MARKERS):
        return  # a folder holding only a user's episodes.parquet, not a probecommit run directory
    if not (run_dir / "manifest.json").is_file():
        raise EpisodeTableError(f"run directory {run_dir} has no manifest.json: the run is incomplete "
                                "(rerun the command that made it to finish it)")
    try:
        verify_files(run_dir / "manifest.json", ("episodes.parquet", "config.yaml"))
    except ManifestError as exc:
        raise EpisodeTableError(str(exc)) from None


def _load(path: Path) -> tuple[pd.DataFrame, str, bool]:
    if path.is_dir():
        candidate = path / "episodes.parquet"
        if not candidate.exists():
            raise EpisodeTableError(f"run directory {path} has no episodes.parquet")
        _check_intact(path)
        path = candidate
    if not path.exists():
        raise EpisodeTableError(f"no episode table at {path}")
    suffix = path.suffix.lower()
    try:
        if suffix in (".parquet", ".pq"):
            return pd.read_parquet(path), str(path), False
        if suffix in (".csv", ".txt"):
            # Read everything as text first: type problems are then reported by
            # column and row instead of as a pandas parser error.
            frame = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
            if len(frame.columns) == 1 and ";" in str(frame.columns[0]):
                raise EpisodeTableError(
                    f"{path}: the header has no commas but has ';' ({str(frame.columns[0])[:60]!r}...): the file looks "
                    "semicolon-separated (a decimal-comma locale); save it with ',' between columns and '.' decimals")
            return frame, str(path), True
    except EpisodeTableError:
        raise
    except (OSError, ValueError, pa.ArrowException) as exc:
        raise EpisodeTableError(f"cannot read episode table {path}: {exc}") from exc
    raise EpisodeTableError(f"unsupported episode table format {path.suffix!r} for {path}; "
                            "use a run directory, .parquet or .csv")


_NA_TEXT = {"", "nan", "NaN", "NA", "N/A", "null", "None", "none"}


def _numeric(df: pd.DataFrame, name: str, csv: bool, source: str) -> pd.Series:
    col = df[name]
    if pd.api.types.is_bool_dtype(col):
        return col.astype(float)
    if pd.api.types.is_numeric_dtype(col):
        return col.astype(float)
    text = col.astype(object)
    is_na = text.isna() | text.map(lambda v: isinstance(v, str) and v.strip() in _NA_TEXT)
    values = pd.to_numeric(text.where(~is_na, np.nan), errors="coerce")
    bad = values.isna() & ~is_na
    if bad.any():
        row = int(np.flatnonzero(bad.to_numpy())[0])
        raise EpisodeTableError(f"{source}: column '{name}' must be numeric ({_TYPES[name]}), "
                                f"found {text.iloc[row]!r} at {_where(row, csv)}")
    return values.astype(float)


def _integer(df: pd.DataFrame, name: str, csv: bool, source: str) -> pd.Series:
    values = _numeric(df, name, csv, source)
    nan = values.isna().to_numpy()
    if nan.any():
        row = int(np.flatnonzero(nan)[0])
        raise EpisodeTableError(f"{source}: column '{name}' is empty at {_where(row, csv)}")
    # Exact integers only: beyond 2**53 a float no longer holds one, and inf has none.
    huge = (~np.isfinite(values.to_numpy(float))) | (np.abs(values.to_numpy(float)) > 2**53)
    if huge.any():
        row = int(np.flatnonzero(huge)[0])
        raise EpisodeTableError(f"{source}: column '{name}' must be a finite integer below 2**53, "
                                f"found {df[name].iloc[row]!r} at {_where(row, csv)}")
    frac = (values != np.round(values)).to_numpy()
    if frac.any():
        row = int(np.flatnonzero(frac)[0])
        raise EpisodeTableError(f"{source}: column '{name}' must be an integer, "
                                f"found {df[name].iloc[row]!r} at {_where(row, csv)}")
    neg = (values < 0).to_numpy()
    if neg.any():
        row = int(np.flatnonzero(neg)[0])
        raise EpisodeTableError(f"{source}: column '{name}' must be >= 0, "
                                f"found {df[name].iloc[row]!r} at {_where(row, csv)}")
    return values.astype(np.int64)


_TRUE = {"true", "1", "1.0", "yes", "t", "y"}
_FALSE = {"false", "0", "0.0", "no", "f", "n"}


def _boolean(df: pd.DataFrame, name: str, csv: bool, source: str) -> pd.Series | None:
    col = df[name]
    if pd.api.types.is_bool_dtype(col) and not col.isna().any():
        return col.astype(bool)
    out = []
    for row, v in enumerate(col.astype(object)):
        if isinstance(v, (bool, np.bool_)):
            out.append(bool(v))
            continue
        if v is None or v is pd.NA or (isinstance(v, float) and np.isnan(v)):
            # Incomplete (an empty CSV cell, a NaN, a nullable boolean's NA alike): derive from the intervals.
            return None
        t = str(v).strip().lower()
        if t in _NA_TEXT or t == "":
            return None
        if t in _TRUE:
            out.append(True)
        elif t in _FALSE:
            out.append(False)
        else:
            raise EpisodeTableError(f"{source}: column '{name}' must be true/false or 1/0, "
                                    f"found {v!r} at {_where(row, csv)}")
    return pd.Series(out, index=col.index, dtype=bool)


def validate_episodes(table: pd.DataFrame, source: str = "episode table", *, csv: bool = False,
                      structure: bool = True, loss: str | None = None) -> pd.DataFrame:
    """Validate an in-memory episode table and return its normalized copy.

    The returned table keeps every row (failed ones included, see
    :func:`ok_episodes`), has ``instance_id`` as string, ``repeat``/``k`` as
    int64, every float column of the schema as float64, ``status`` filled
    (``"ok"`` when absent) and ``covered``/``escaped`` derived from the
    intervals when absent or incomplete. ``attrs`` carries ``source``,
    ``n_total`` and ``n_failed``.

    Args:
        table: The raw table.
        source: Name used in error messages (a path).
        csv: Whether row numbers should also be given as CSV line numbers.
        structure: Check the table's structure (no duplicate episode, equal repeats per
            instance and budget, every instance at every budget). A caller that re-commits
            the same episodes many times (a margin search) checks it once and passes False
            after; the normalization and the value checks always run.
        loss: ``"binary"`` (failure 0/1, predicted a fraction in [0, 1]), ``"continuous"``
            (a miss >= 0), or None to infer it (see :func:`_check_losses`).

    Returns:
        The validated table.

    Raises:
        EpisodeTableError: With one message naming the problem.
    """
    df = checked_frame(table, AUDIT_REQUIRED, source, EpisodeTableError, "the audit")
    _check_header(df, source)
    _normalize_keys(df, csv, source)
    ok = _normalize_status(df, csv, source)
    notes: list[str] = []
    df = _normalize_numbers(df, csv, source, notes)
    _check_values(df, ok, csv, source, notes)
    for name in GROUP_COLUMNS:
        if name in df.columns:
            df[name] = df[name].astype(object).where(df[name].notna(), "").astype(str)
    if structure:
        _check_structure(df, [c for c in GROUP_COLUMNS if c in df.columns], csv, source)
    _check_losses(df, ok, source, csv, loss)
    _derive_indicators(df, ok, csv, source, notes)
    if (~ok).any():
        partial = set(df.loc[~ok, "instance_id"]) & set(df.loc[ok, "instance_id"])
        if partial:
            notes.append(f"{len(partial)} instance(s) have failed rows beside successful ones; their cluster coverage "
                         "is over the remaining repeats only, which can only raise it")
    df.attrs = {"source": source, "n_total": int(len(df)), "n_failed": int((~ok).sum()), "notes": notes}
    return df


def check_episode_values(table: pd.DataFrame, source: str = "episode table") -> None:
    """The checks of :func:`validate_episodes` that read a table's values, on a table already in
    the schema's types: status 'ok' or 'failed'; the ok rows' required values finite, of a
    possible magnitude, intervals ordered; the losses of one kind. Nothing is returned.

    Why: a calibration re-executes its runs' commits chunk by chunk and validates each chunk's
    table only to catch a wrong value; the table comes from ``runner.inference.commit``, in the
    schema's types already, and :func:`validate_episodes`' normalized copy of it was thrown
    away: its string and type conversions were most of a chunk's validation (12 of 14 ms at
    3072 rows, issue 42). The structure is checked once per run, by :func:`validate_episodes`.

    Raises:
        EpisodeTableError: As :func:`validate_episodes` would for the same values.
    """
    status = table["status"].to_numpy()
    bad = ~np.isin(status, _OK_STATUS)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise _status_error(source, status[row], row, False)
    ok = status == "ok"
    _check_values(table, ok, False, source, [])
    _check_losses(table, ok, source, False, None)


def _check_header(df: pd.DataFrame, source: str) -> None:
    """pandas renames a repeated CSV header "x" to "x.1": a column given twice is an error, not a rename."""
    renamed = [c for c in df.columns if "." in c and c.rsplit(".", 1)[1].isdigit() and c.rsplit(".", 1)[0] in df.columns]
    if renamed:
        raise EpisodeTableError(f"{source}: column '{renamed[0].rsplit('.', 1)[0]}' appears more than once in the header")


def _normalize_keys(df: pd.DataFrame, csv: bool, source: str) -> None:
    """``instance_id`` as non-empty strings (integer-like ids from a user's log, 1 or 2.0, become
    '1', '2'); ``repeat`` and ``k`` as int64. In place."""
    ids = df["instance_id"]
    id_na = ids.isna() | ids.astype(str).str.strip().isin(["", "nan", "None"])
    if id_na.any():
        row = int(np.flatnonzero(id_na.to_numpy())[0])
        raise EpisodeTableError(f"{source}: column 'instance_id' is empty at {_where(row, csv)}")
    if pd.api.types.is_float_dtype(ids) and np.all(ids == np.round(ids)):
        ids = ids.astype(np.int64)
    df["instance_id"] = ids.astype(str).str.strip()
    for name in ("repeat", "k"):
        df[name] = _integer(df, name, csv, source)


def _status_error(source: str, value: Any, row: int, csv: bool) -> EpisodeTableError:
    """The one message for a status that is neither 'ok' nor 'failed' (normalized and value-only checks alike)."""
    return EpisodeTableError(f"{source}: column 'status' must be 'ok' or 'failed', found {value!r} at {_where(row, csv)}")


def _normalize_status(df: pd.DataFrame, csv: bool, source: str) -> np.ndarray:
    """``status`` as 'ok' or 'failed' ('ok' when absent or blank), in place; the ok rows ``[R]``.
    Read first: NaN outcomes are allowed on failed episodes."""
    if "status" in df.columns:
        raw = df["status"]
        status = raw.astype(str).str.strip().str.lower()
        status[raw.isna().to_numpy() | (status == "").to_numpy()] = "ok"  # None, NaN and blank cells are ok
        bad = ~status.isin(_OK_STATUS)
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise _status_error(source, df["status"].iloc[row], row, csv)
        df["status"] = status.astype(str)
    else:
        df["status"] = "ok"
    return (df["status"] == "ok").to_numpy()


def _normalize_numbers(df: pd.DataFrame, csv: bool, source: str, notes: list[str]) -> pd.DataFrame:
    """Every numeric schema column as numbers. A required one must read; an optional column the
    audit does not need must not block it: an unreadable one is dropped, and said in ``notes``."""
    for c in EPISODE_COLUMNS:
        numeric = c.name in df.columns and (pa.types.is_floating(c.type) or
                                            (pa.types.is_integer(c.type) and c.name not in ("repeat", "k")))
        if not numeric:
            continue
        if c.name in AUDIT_REQUIRED:
            df[c.name] = _numeric(df, c.name, csv, source)
            continue
        try:
            df[c.name] = _numeric(df, c.name, csv, source)  # optional integer columns stay float if they have gaps
        except EpisodeTableError as exc:
            df = df.drop(columns=[c.name])
            notes.append(f"optional column '{c.name}' ignored: {str(exc).split(': ', 1)[-1]}")
    return df


def _check_values(df: pd.DataFrame, ok: np.ndarray, csv: bool, source: str, notes: list[str]) -> None:
    """The ok rows' required values are finite and of a possible magnitude, and their intervals
    ordered; a retained interval wider than the hull is counted in ``notes``."""
    for name in FINITE_REQUIRED:
        bad = ~np.isfinite(df[name].to_numpy()) & ok
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            kind = "NaN" if np.isnan(df[name].iloc[row]) else "an infinite value"
            raise EpisodeTableError(f"{source}: column '{name}' has {kind} at {_where(row, csv)} "
                                    f"({int(bad.sum())} ok row(s) affected); mark the episode "
                                    "status 'failed' or drop it")
    for name in FINITE_REQUIRED:
        big = (np.abs(df[name].to_numpy()) > MAX_MAGNITUDE) & ok
        if big.any():
            row = int(np.flatnonzero(big)[0])
            raise EpisodeTableError(f"{source}: column '{name}' has {df[name].iloc[row]!r} at {_where(row, csv)}, "
                                    f"beyond the magnitude any episode value can have ({MAX_MAGNITUDE:g})")
    for lo, hi in (("retained_lo", "retained_hi"), ("hull_lo", "hull_hi")):
        bad = (df[lo] > df[hi]).to_numpy() & ok
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise EpisodeTableError(f"{source}: {lo} > {hi} at {_where(row, csv)} "
                                    f"({df[lo].iloc[row]!r} > {df[hi].iloc[row]!r})")
    # A retained interval wider than the particle hull is legitimate only for a grown set (a
    # conformal threshold t > 1); such rows can be covered and escaped at once. Counted, and
    # said in the report, never silent.
    wider = ((df["retained_lo"] < df["hull_lo"] - 1e-9) | (df["retained_hi"] > df["hull_hi"] + 1e-9)).to_numpy() & ok
    if wider.any():
        both = wider & ((df["z_true"] < df["hull_lo"]) | (df["z_true"] > df["hull_hi"])).to_numpy() & \
            ((df["retained_lo"] <= df["z_true"]) & (df["z_true"] <= df["retained_hi"])).to_numpy()
        notes.append(f"{int(wider.sum())} row(s) have a retained interval wider than the particle hull (a grown set, "
                     f"conformal threshold t > 1); {int(both.sum())} of them are both covered and escaped")


def _check_structure(df: pd.DataFrame, groups: list[str], csv: bool, source: str) -> None:
    """No duplicate episode, equal repeats per instance and budget, every instance at every budget."""
    dup = df.duplicated(groups + list(KEY_COLUMNS), keep="first")
    if dup.any():
        row = int(np.flatnonzero(dup.to_numpy())[0])
        key = ", ".join(f"{c}={df[c].iloc[row]!r}" for c in groups + list(KEY_COLUMNS))
        raise EpisodeTableError(f"{source}: duplicate episode ({key}) at {_where(row, csv)}")
    _check_repeats(df, groups, source)
    _check_budgets(df, groups, source)


def _derive_indicators(df: pd.DataFrame, ok: np.ndarray, csv: bool, source: str, notes: list[str]) -> None:
    """``covered`` and ``escaped`` recomputed from the intervals (closed), never trusted: a given
    column that contradicts them is replaced by the recomputed value, and that is said. In place."""
    z = df["z_true"]
    derived_cov = (df["retained_lo"] <= z) & (z <= df["retained_hi"])
    derived_esc = (z < df["hull_lo"]) | (z > df["hull_hi"])
    for name, derived in (("covered", derived_cov), ("escaped", derived_esc)):
        given = _boolean(df, name, csv, source) if name in df.columns else None
        if given is not None:
            differ = (given.to_numpy() != derived.to_numpy()) & ok
            if differ.any():
                row = int(np.flatnonzero(differ)[0])
                notes.append(f"column '{name}' contradicts the intervals on {int(differ.sum())} ok row(s) (first at "
                             f"{_where(row, csv)}: given {bool(given.iloc[row])}, intervals give "
                             f"{bool(derived.iloc[row])}); the value recomputed from the intervals is used")
        df[name] = derived.astype(bool)


def _check_losses(df: pd.DataFrame, ok: np.ndarray, source: str, csv: bool, loss: str | None) -> None:
    """``predicted`` and ``realized`` are losses of one kind: never negative; for a binary task
    (declared, or inferred when every realized value is 0 or 1) realized is 0/1 and predicted
    a failure fraction in [0, 1]. Undeclared, realized values that are 0/1 on most rows but
    not all with the others whole numbers, or only 0 and 100 (a percent column), are refused:
    they are not one kind of loss.
    """
    if loss is not None and loss not in LOSS_KINDS:
        raise EpisodeTableError(f"{source}: loss must be one of {', '.join(LOSS_KINDS)}, got {loss!r}")
    pred, real = df["predicted"].to_numpy(float), df["realized"].to_numpy(float)

    def first(mask: np.ndarray, name: str, why: str) -> None:
        mask = mask & ok
        if mask.any():
            row = int(np.flatnonzero(mask)[0])
            raise EpisodeTableError(f"{source}: column '{name}' has {df[name].iloc[row]!r} at {_where(row, csv)}: "
                                    f"{why} ({int(mask.sum())} ok row(s) affected)")

    first(pred < 0, "predicted", "a predicted loss (failure fraction or miss) is never negative")
    first(real < 0, "realized", "a realized loss (failure or miss) is never negative")
    binary01 = np.isin(real, (0.0, 1.0))
    if loss is None and ok.any():
        if np.all(np.isin(real[ok], (0.0, 100.0))) and np.any(real[ok] == 100.0):
            first(real == 100.0, "realized", "the column holds only 0 and 100, a failure in percent; give failure "
                  "as 0/1 (or declare the loss continuous, --loss continuous, if 100 is a miss)")
        share = binary01[ok].mean()
        if 0.5 <= share < 1.0:  # a stray integer among 0/1 failures (a continuous miss is rarely one)
            first(~binary01 & (real == np.round(real)), "realized", "the other rows are 0/1 failures; a binary task's realized is 0 or 1 "
                  "(declare the loss continuous, --loss continuous, if the column is a miss)")
        loss = "binary" if share == 1.0 else "continuous"
    if loss == "binary":
        first(~binary01, "realized", "a binary task's realized failure is 0 or 1")
        first(pred > 1, "predicted", "a binary task's predicted score is a failure fraction in [0, 1]")


def _check_repeats(df: pd.DataFrame, groups: list[str], source: str) -> None:
    """Every instance must carry the same number of repeats at a budget (per group).

    A trajectory marked failed anywhere (e.g. our runner's ``rollout`` row when
    the engine failed mid-probe) counts as present at every budget, since its
    absence is explained; groups made only of failed rows are not checked.
    """
    failed = df["status"] == "failed"
    all_failed_groups = set()
    if groups:
        ok_any = (~failed).groupby([df[g] for g in groups]).any()
        all_failed_groups = {k if isinstance(k, tuple) else (k,) for k, v in ok_any.items() if not v}
    failed_traj = df.loc[failed, ["instance_id", "repeat"]].drop_duplicates()
    keyed = df[groups + ["k", "instance_id", "repeat"]]
    if groups and all_failed_groups:
        gk = list(map(tuple, df[groups].to_numpy()))
        keyed = keyed.loc[[g not in all_failed_groups for g in gk]]
    if len(failed_traj):
        # Add each failed trajectory to every (group, k) its instance appears in.
        cells = keyed[groups + ["k", "instance_id"]].drop_duplicates()
        extra = cells.merge(failed_traj, on="instance_id")
        keyed = pd.concat([keyed, extra], ignore_index=True)
    counts = keyed.groupby(groups + ["k", "instance_id"], sort=True)["repeat"].nunique()
    per_budget = counts.groupby(level=list(range(len(groups) + 1)))
    for budget_key, c in per_budget:
        if c.nunique() > 1:
            modal = int(c.mode().iloc[0])
            odd = c[c != modal]
            inst = odd.index[0][-1]
            budget_key = budget_key if isinstance(budget_key, tuple) else (budget_key,)
            where = ", ".join(f"{g}={v!r}" for g, v in zip(groups + ["k"], budget_key))
            raise EpisodeTableError(
                f"{source}: repeats of unequal count at {where}: instance {inst!r} has "
                f"{int(odd.iloc[0])} repeat(s) but most instances have {modal} "
                f"({len(odd)} instance(s) differ); cluster coverage needs every repeat")


def _check_budgets(df: pd.DataFrame, groups: list[str], source: str) -> None:
    """Every instance of a group must appear at every budget the group reports (none silently dropped)."""
    keyed = df[df["status"] != "failed"]
    for key, part in (keyed.groupby(groups, sort=False) if groups else [((), keyed)]):
        budgets = set(part["k"].unique())
        have = part.groupby("instance_id")["k"].agg(lambda ks: set(ks))
        missing = have[have.map(lambda ks: ks != budgets)]
        if len(missing):
            inst = missing.index[0]
            lacking = sorted(int(k) for k in budgets - missing.iloc[0])
            where = ", ".join(f"{g}={v!r}" for g, v in zip(groups, key if isinstance(key, tuple) else (key,)))
            raise EpisodeTableError(f"{source}: instance {inst!r} has no rows at budget(s) {lacking}"
                                    f"{' (' + where + ')' if where else ''} while other instances do "
                                    f"({len(missing)} instance(s) affected); per-budget metrics need every instance")


def read_episodes(path: str | Path, *, loss: str | None = None) -> pd.DataFrame:
    """Read and validate an episode table.

    Args:
        path: A run directory (its ``episodes.parquet``), or a Parquet/CSV file
            with the documented episode columns (a real robot's log).

    Returns:
        The validated table (all rows, failed ones included; metrics exclude
        them). ``attrs``: ``source``, ``n_total``, ``n_failed``.

    Raises:
        EpisodeTableError: Unreadable file, missing column(s), a non-numeric or
            NaN value where a number is required (column and first row named),
            ``retained_lo > retained_hi``, duplicate episodes, or repeats of
            unequal count across instances at a budget.
    """
    df, source, csv = _load(Path(path))
    return validate_episodes(df, source, csv=csv, loss=loss)


def ok_episodes(df: pd.DataFrame) -> pd.DataFrame:
    """Rows whose status is not ``failed`` (all rows when there is no status column)."""
    if "status" not in df.columns:
        return df
    return df.loc[df["status"].astype(str) != "failed"]


def group_columns(df: pd.DataFrame, extra: Iterable[str] = ()) -> list[str]:
    """Grouping columns present in ``df`` (method, variant) plus ``extra``."""
    return [c for c in GROUP_COLUMNS if c in df.columns] + list(extra)
