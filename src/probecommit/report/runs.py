"""A browser of run directories: what ran, with what code, and what came out (``probecommit runs``).

:func:`list_runs` finds the run directories under a folder and reads one row for each
(name, task, engine, episodes, headline numbers at the last budget, code identity,
status); :func:`compare_runs` sets two runs side by side: the config fields that differ
and, per method and budget, the metrics of both with their difference, a paired
cluster-bootstrap interval when the two runs hold the same instances (same ids and
truths), so the same episodes are compared.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from probecommit.errors import UserError
from probecommit.store.rundir import flatten_dotted

#: Columns of the episode table that the headline numbers read.
_HEADLINE_COLUMNS = ["instance_id", "repeat", "k", "method", "status", "realized", "predicted", "covered", "escaped"]
#: The method whose last budget is the run's headline (else the first method the run has).
HEADLINE_METHOD = "probe_robust"
#: Metrics of a comparison: the episode column, or ``optimism`` (realized - predicted per episode).
COMPARED = ("failure", "optimism", "coverage")


class RunsError(UserError, ValueError):
    """A folder holds no run, or a run to compare is not one (the message names it)."""


def find_runs(root: str | Path, max_depth: int = 3) -> list[Path]:
    """Run directories (a ``config.yaml`` beside ``shards/`` or ``manifest.json``) under ``root``,
    ``root`` itself included, at most ``max_depth`` levels down, sorted by path."""
    root = Path(root)
    if not root.is_dir():
        raise RunsError(f"{root} is not a directory")
    found: list[Path] = []
    frontier = [(root, 0)]
    while frontier:
        folder, depth = frontier.pop()
        if _is_run(folder):
            found.append(folder)
            continue
        if depth < max_depth:
            try:
                children = [c for c in folder.iterdir() if c.is_dir() and not c.is_symlink() and c.name != "shards"]
            except OSError:
                continue
            frontier.extend((c, depth + 1) for c in children)
    return sorted(found)


def _is_run(folder: Path) -> bool:
    return (folder / "config.yaml").is_file() and ((folder / "manifest.json").is_file() or (folder / "shards").is_dir())


def _episodes(folder: Path) -> pd.DataFrame | None:
    path = folder / "episodes.parquet"
    if not path.is_file():
        return None
    import pyarrow.parquet as pq

    have = set(pq.read_schema(path).names)
    return pd.read_parquet(path, columns=[c for c in _HEADLINE_COLUMNS if c in have])


def headline(episodes: pd.DataFrame) -> dict[str, Any]:
    """The run's headline at its last budget: the probe method's failure (or miss), optimism and coverage."""
    ok = episodes[episodes["status"] == "ok"] if "status" in episodes else episodes
    methods = list(dict.fromkeys(ok["method"])) if "method" in ok else []
    method = HEADLINE_METHOD if HEADLINE_METHOD in methods else (methods[0] if methods else None)
    part = ok[ok["method"] == method] if method is not None else ok
    if part.empty:
        return {"method": method, "k": None, "failure": np.nan, "optimism": np.nan, "coverage": np.nan}
    last = part[part["k"] == part["k"].max()]
    failure = float(last["realized"].mean())
    return {"method": method, "k": int(last["k"].iloc[0]), "failure": failure,
            "optimism": failure - float(last["predicted"].mean()), "coverage": float(last["covered"].mean())}


def _code(manifest: dict[str, Any]) -> str:
    commit = manifest.get("git_commit")
    if commit:
        return commit[:10] + ("+dirty" if manifest.get("git_dirty") else "")
    code = manifest.get("code_sha256")
    return f"src:{code[:8]}" if code else "?"


def run_row(folder: Path) -> dict[str, Any]:
    """One row of :func:`list_runs` for the run directory ``folder``."""
    config = yaml.safe_load((folder / "config.yaml").read_text()) or {}
    simulator = config.get("simulator") or {}
    row: dict[str, Any] = {"run": str(folder), "name": config.get("name"), "task": config.get("task"),
                           "engine": simulator.get("engine"), "budget": (config.get("probes") or {}).get("budget")}
    manifest_path = folder / "manifest.json"
    if manifest_path.is_file():
        try:
            manifest = json.loads(manifest_path.read_text())
        except ValueError:
            manifest = {}
        episodes = _episodes(folder)
        failed = int((episodes["status"] != "ok").sum()) if episodes is not None and "status" in episodes else 0
        row["status"] = "complete" if manifest else "corrupt manifest"
        if failed:
            row["status"] += f" ({failed} failed)"
        row["code"] = _code(manifest)
        row["episodes"] = len(episodes) if episodes is not None else 0
        row.update({k: v for k, v in (headline(episodes) if episodes is not None else {}).items()})
    else:
        shards = folder / "shards"
        done = len(list(shards.glob("*/episodes.parquet"))) if shards.is_dir() else 0
        code = (shards / "CODE").read_text().strip() if (shards / "CODE").is_file() else ""
        row.update(status=f"incomplete ({done} units done)", code=f"src:{code[:8]}" if code else "?", episodes=0)
    overrides = folder / "overrides.yaml"
    if overrides.is_file():
        row["overrides"] = " ".join((yaml.safe_load(overrides.read_text()) or {}).get("overrides") or [])
    return row


def list_runs(root: str | Path) -> pd.DataFrame:
    """A table of every run directory under ``root`` (see the module docstring)."""
    rows = [run_row(folder) for folder in find_runs(root)]
    columns = ["run", "name", "task", "engine", "budget", "episodes", "method", "k", "failure", "optimism",
               "coverage", "code", "status", "overrides"]
    frame = pd.DataFrame(rows)
    return frame.reindex(columns=[c for c in columns if c in frame.columns or c in ("run", "status")])


# ----------------------------------------------------------------------------- compare


def config_diff(a: Path, b: Path) -> pd.DataFrame:
    """The config fields whose values differ between two run directories (``field``, ``a``, ``b``)."""
    fa = flatten_dotted(yaml.safe_load((a / "config.yaml").read_text()) or {})
    fb = flatten_dotted(yaml.safe_load((b / "config.yaml").read_text()) or {})
    rows = [{"field": key, "a": fa.get(key, "(unset)"), "b": fb.get(key, "(unset)")}
            for key in sorted(set(fa) | set(fb)) if fa.get(key, "(unset)") != fb.get(key, "(unset)")]
    return pd.DataFrame(rows, columns=["field", "a", "b"])


def same_instances(a: Path, b: Path) -> bool:
    """Whether two runs hold the same instances: the same ids with the same truths (and contexts)."""
    ia, ib = pd.read_parquet(a / "instances.parquet"), pd.read_parquet(b / "instances.parquet")
    if list(ia.columns) != list(ib.columns) or len(ia) != len(ib):
        return False
    ia = ia.sort_values("instance_id").reset_index(drop=True)
    ib = ib.sort_values("instance_id").reset_index(drop=True)
    return bool(ia.astype(str).equals(ib.astype(str)))


def _metric_frame(episodes: pd.DataFrame) -> pd.DataFrame:
    ok = episodes[episodes["status"] == "ok"].copy()
    return ok.assign(failure=ok["realized"].astype(float), optimism=ok["realized"] - ok["predicted"],
                     coverage=ok["covered"].astype(float))


@dataclass
class Comparison:
    """Two runs side by side. ``metrics`` has, per method, budget and metric, both values, ``diff`` = b - a
    and, when ``paired``, ``lo``/``hi`` of the paired cluster-bootstrap interval."""

    a: Path
    b: Path
    config: pd.DataFrame
    metrics: pd.DataFrame
    paired: bool


def compare_runs(a: str | Path, b: str | Path, *, resamples: int = 2000, seed: int = 0,
                 budgets: list[int] | None = None) -> Comparison:
    """Compare two complete run directories (see the module docstring)."""
    from probecommit.audit.stats import paired_bootstrap

    a, b = Path(a), Path(b)
    for run in (a, b):
        if not (run / "manifest.json").is_file() or not (run / "config.yaml").is_file():
            raise RunsError(f"{run} is not a complete run directory (no manifest.json)")
    ea, eb = _metric_frame(pd.read_parquet(a / "episodes.parquet")), _metric_frame(pd.read_parquet(b / "episodes.parquet"))
    paired = same_instances(a, b)
    rows = []
    methods = [m for m in dict.fromkeys(ea["method"]) if m in set(eb["method"])]
    for method in methods:
        ma, mb = ea[ea["method"] == method], eb[eb["method"] == method]
        ks = sorted(set(ma["k"]) & set(mb["k"]))
        for k in ks if budgets is None else [k for k in ks if k in budgets]:
            ga, gb = ma[ma["k"] == k], mb[mb["k"] == k]
            for metric in COMPARED:
                row = {"method": method, "k": int(k), "metric": metric, "a": float(ga[metric].mean()),
                       "b": float(gb[metric].mean())}
                row["diff"], row["lo"], row["hi"], row["pairs"] = row["b"] - row["a"], np.nan, np.nan, 0
                if paired:
                    try:
                        d = paired_bootstrap(ga, gb, metric, resamples=resamples, seed=seed, strict=False)
                    except ValueError:  # no common episode at this budget
                        d = None
                    if d is not None:
                        row.update(diff=d.difference.estimate, lo=d.difference.lo, hi=d.difference.hi,
                                   pairs=d.n_pairs)
                rows.append(row)
    return Comparison(a, b, config_diff(a, b), pd.DataFrame(rows), paired)
