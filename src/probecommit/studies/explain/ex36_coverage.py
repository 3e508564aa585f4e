"""Table V's random-probe episode coverage at k = 8 (old model) over E17's fresh draws of the generator (E209; ex36,
issue #36; rule declared in ``docs/decisions.md``, "ex36", before any number was computed).

Why: Table V's ``episode_coverage_random_k8 old`` is one 96-instance draw (Test C) of the generator that also draws
Split B test; E17 asks the same question of Table III's cells over 12 fresh draws of it (``runs.fresh_draws``: the
analytic scene with the MuJoCo scene's boundary, random probes, written by ``Explain.draw_runs``). This step reads
those draws' stored episode tables (no new run) and counts, per draw, the share of Probe-Robust episodes whose truth
is covered at k = 8 and, beside it, at k = 1 (T11's ``coverage k=1``, published, not credited). The analytic redraw
of Split B test is the check row. Every key is :func:`summary` of the stored rows, so ``verify`` recomputes them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import pandas as pd

#: The stored rows (one per draw, the check first), beside results.json.
STORED = "ex36_coverage_rows.parquet"
#: Result group.
GROUP = "ex36_coverage"
#: The check row's run: the analytic redraw of Split B test (``runs.fresh_draws``' first).
CHECK = "analytic_B_test_random"
#: The budgets read, each with the paper's value its range is set beside (k = 8: E209's rule; k = 1: T11's, beside).
PAPER = {8: "tab:testc.episode_coverage_random_k8.old", 1: "T11-audit-trend.coverage_k1"}


def draw_row(draw: str, episodes: pd.DataFrame) -> dict[str, Any]:
    """One draw's row: its name, and per budget k of :data:`PAPER` the Probe-Robust episodes and the share covered."""
    from probecommit.studies.insertion import probe_rows

    out: dict[str, Any] = {"draw": draw}
    for k in sorted(PAPER):
        at = probe_rows(episodes, k)
        out[f"episodes_k{k}"] = int(len(at))
        out[f"coverage_k{k}"] = float(at["covered"].astype(float).mean())
    return out


def draw_rows(runs: Path) -> pd.DataFrame:
    """The check row, then E17's fresh draws in order (those on disk under ``runs``)."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex20 import DRAW_PREFIX

    folders = [Path(runs) / CHECK, *sorted(Path(runs).glob(f"{DRAW_PREFIX}[0-9][0-9]"))]
    return pd.DataFrame([draw_row(f.name, load_run(f).episodes) for f in folders
                         if (f / "episodes.parquet").is_file()])


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """``draws`` (fresh ones), and per budget k: the check row's coverage (``check.k<k>``), the fresh draws' ``min``,
    ``max``, ``mean`` and ``sd`` (``k<k>.*``), the paper's value (``k<k>.paper``) and whether it lies within [min, max]
    (``k<k>.inside``, 1 = yes). ``holds`` is k = 8's: E209's rule."""
    from probecommit.studies.paper_values import value

    check, fresh = rows[rows["draw"] == CHECK], rows[rows["draw"] != CHECK]
    out: dict[str, Any] = {"draws": float(len(fresh))}
    for k in sorted(PAPER):
        v = fresh[f"coverage_k{k}"].to_numpy(float)
        if len(check):
            out[f"check.k{k}"] = float(check[f"coverage_k{k}"].iloc[0])
        if not len(v):
            continue
        paper = float(value(PAPER[k]))
        out[f"k{k}.min"], out[f"k{k}.max"], out[f"k{k}.mean"] = float(v.min()), float(v.max()), float(v.mean())
        out[f"k{k}.sd"] = float(v.std(ddof=1)) if len(v) > 1 else float("nan")
        out[f"k{k}.paper"] = paper
        out[f"k{k}.inside"] = float(v.min() <= paper <= v.max())
    if "k8.inside" in out:
        out["holds"] = out["k8.inside"]
    return out


def run(job: Any) -> None:
    """E209 (set aside after ``Explain.draw_runs`` wrote the draws): stored rows and keys (seconds)."""
    job.progress("explain: Table V's random k = 8 coverage over fresh draws (E209)", 0, 1)
    rows = draw_rows(job.runs)
    if len(rows):
        job.stored[STORED] = rows
        job.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "draw_rows", "draw_row", "STORED", "GROUP", "PAPER")
