"""The margin judged on fresh calibration episodes at each candidate gamma (E190, E191; ex30, issue #36; rules
declared in ``docs/decisions.md``, "ex30").

Why: the paper's margin is the largest gamma whose mean predicted failure over the calibration episodes is at least
their realized failure. Ours recommits the same stored probes under every candidate, and our insertion outcome is a
deterministic engine query of truth and aim, so the realized curve is nearly monotone in gamma and the search cannot
stop on a lucky draw: the held-out half is no more optimistic than the half the margin was fitted on (ex28). If each
candidate's calibration episodes were run afresh (fresh tap noise: fresh beliefs, aims and outcomes), "the largest
gamma that passes" would stop where a draw favoured it, a winner's curse. A fresh episode of an instance is emulated
as one more draw of its stored repeats: per candidate gamma independently, each calibration instance's repeats are
drawn with replacement, and the paper's rule (``audit.margin.select_margin``) runs on those draws' sums.

E190 applies it to T14's 50 re-splits of the frozen pool at k = 5 (the insertion study's halves and thresholds; the
held-out half's stored episodes at the selected gamma); E191 to Table III's random calibration (its thresholds t_k over
the random budgets), Table III's calibrated cells then computed at the median selected gamma as E82 computes them at
0.62. Every key is :func:`summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

import warnings
from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.conformal import budget_thresholds
from probecommit.audit.io import ok_episodes
from probecommit.audit.margin import GAMMA_GRID, margin_candidates, select_margin

#: The stored rows, beside results.json.
STORED = "ex30_fresh_rows.parquet"
#: Result group.
GROUP = "ex30_fresh"
#: Noise draws per re-split (E190) and of Table III's calibration (E191, odd: its median is a grid value).
SHARE_DRAWS, TABLE_DRAWS = 20, 21
#: The declared seeds of the noise draws.
SHARE_SEED, TABLE_SEED = 190, 191
#: The frozen pool T14's re-splits are drawn from, and Table III's random runs.
POOL, TABLE_CAL, TABLE_TEST = "B_pool_cover", "B_cal_random", "B_test_random"
#: The re-splits' budget (the insertion study's ``resplit_table``).
SHARE_BUDGET = 5
#: The claim's own tolerance on the share (E190's rule).
SHARE_TOL = 0.10
#: The columns a recommitted table is reduced from.
COLUMNS = ("instance_id", "repeat", "k", "status", "predicted", "realized")
#: Table III's cells E191 is judged on.
TABLE_K = (2, 3)


class GridSums:
    """Per candidate gamma, instance and repeat: the sums of predicted and realized failure over the ok episodes of
    the budgets committed, and their count (arrays gammas x instances x repeats; a missing trajectory counts 0)."""

    def __init__(self, gammas: list[float], tables: Sequence[pd.DataFrame]) -> None:
        every = pd.concat([t.assign(gamma=g) for g, t in zip(gammas, tables)], ignore_index=True)
        sums = ok_episodes(every).groupby(["gamma", "instance_id", "repeat"]).agg(
            p=("predicted", "sum"), r=("realized", "sum"), n=("predicted", "size"))
        self.gammas = list(gammas)
        self.ids = np.array(sorted(every["instance_id"].unique()))
        repeats = sorted(every["repeat"].unique())  # a failed trajectory stays a slot a draw can take
        full = pd.MultiIndex.from_product([self.gammas, self.ids, repeats], names=sums.index.names)
        shape = (len(self.gammas), len(self.ids), len(repeats))
        sums = sums.reindex(full, fill_value=0)
        self.p, self.r, self.n = (sums[c].to_numpy(float).reshape(shape) for c in ("p", "r", "n"))

    def rows_of(self, ids: np.ndarray) -> np.ndarray:
        """Positions of ``ids`` in the instance axis."""
        return np.searchsorted(self.ids, np.asarray(ids))

    def optimism(self, at: int, rows: np.ndarray) -> float:
        """Mean realized - predicted failure over the episodes of ``rows`` at the ``at``-th gamma."""
        return float((self.r[at, rows].sum() - self.p[at, rows].sum()) / self.n[at, rows].sum())


def grid_sums(cal: Any, thresholds: dict[int, float]) -> GridSums:
    """Every grid gamma's commit of ``cal`` (a run from ``runner.calibration.load_for_commit``) under the
    thresholds ``{k: t_k}``, as sums over the budgets they name."""
    gammas = margin_candidates(GAMMA_GRID)
    return GridSums(gammas, cal.commit(*[(dict(thresholds), g) for g in gammas], keep=[COLUMNS] * len(gammas)))


def loaded(run: Any, budgets: Sequence[int]) -> tuple[Any, pd.DataFrame]:
    """``run`` ready for commits at ``budgets`` (its beliefs computed once) and its worst-repeat scores."""
    from probecommit.runner.calibration import calibration_scores, load_for_commit

    cal = load_for_commit(run, True, None, None, list(budgets))
    return cal, calibration_scores(cal)


def select(sums: GridSums, rows: np.ndarray, draws: np.ndarray | None) -> tuple[int, float]:
    """The paper's rule on ``rows``' episodes, each candidate's repeats drawn by ``draws`` (gammas x rows x
    repeats, repeat positions; None: the stored repeats): the selected gamma's position and the drawn episodes'
    mean optimism there."""
    p, r, n = sums.p[:, rows], sums.r[:, rows], sums.n[:, rows]
    if draws is not None:
        p, r, n = (np.take_along_axis(x, draws, axis=2) for x in (p, r, n))
    p_sum, r_sum, n_sum = (x.sum(axis=(1, 2)) for x in (p, r, n))
    m = rule_stop(sums.gammas, p_sum, r_sum)
    return m, float((r_sum[m] - p_sum[m]) / n_sum[m])


def rule_stop(gammas: Sequence[float], p_sum: np.ndarray, r_sum: np.ndarray) -> int:
    """The position of the gamma the paper's rule (``audit.margin.select_margin``, its slack included) selects from
    each candidate's summed predicted and realized failure (``p_sum``, ``r_sum`` in ``gammas``' order); the smallest
    grid value when none passes, as the search does (shared with ex33's aim-noise search)."""
    at = {g: m for m, g in enumerate(gammas)}

    def evaluate(gamma: float) -> pd.DataFrame:
        return pd.DataFrame({"predicted": [p_sum[at[gamma]]], "realized": [r_sum[at[gamma]]]})

    with warnings.catch_warnings():  # a draw no grid value satisfies takes the smallest, as the search does
        warnings.filterwarnings("ignore", message="no margin on the grid", category=RuntimeWarning)
        return at[select_margin(evaluate, gammas).gamma]


def draw_repeats(rng: np.random.Generator, sums: GridSums, count: int) -> np.ndarray:
    """One fresh-episode draw: per gamma and instance, ``count`` rows' repeats drawn with replacement."""
    return rng.integers(0, sums.p.shape[2], size=(len(sums.gammas), count, sums.p.shape[2]))


def split_rows(sums: GridSums, n: int, cal: np.ndarray, test: np.ndarray, level: float,
               rng: np.random.Generator, draws: int) -> list[dict[str, float]]:
    """One re-split's rows: without noise (``draw`` -1) and under ``draws`` fresh-episode draws, the selected gamma,
    the calibration half's optimism there (as drawn and on its stored episodes) and the held-out half's."""
    c, t = sums.rows_of(cal), sums.rows_of(test)
    out = []
    for d in range(-1, draws):
        m, drawn = select(sums, c, None if d < 0 else draw_repeats(rng, sums, len(c)))
        held = sums.optimism(m, t)
        out.append({"part": "share", "index": n, "draw": d, "level": level, "gamma": sums.gammas[m],
                    "cal_drawn": drawn, "cal_true": sums.optimism(m, c), "held": held, "optimistic": float(held > 0)})
    return out


def resplit_levels(pool_dir: Any, alpha: float, count: int, seed: int) -> tuple[Any, list, Any, list[float]]:
    """The insertion study's ``count`` re-splits of the pool at k = 5 as ``resplit_table`` draws them: the loaded
    run, its halves (calibration, held-out ids), the run ready for commits at k = 5 and each split's t_5 from its
    calibration half (shared with ex33's aim-noise re-splits)."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex5_calibration import split_halves

    pool = load_run(pool_dir)
    halves = split_halves(pool.instances["instance_id"].to_numpy(), count, seed)
    cal, scores = loaded(pool, [SHARE_BUDGET])
    levels = [float(budget_thresholds(scores.loc[ids], alpha, [SHARE_BUDGET])[SHARE_BUDGET]) for ids, _ in halves]
    return pool, halves, cal, levels


def share_rows(pool_dir: Any, alpha: float, count: int, seed: int, draws: int = SHARE_DRAWS) -> pd.DataFrame:
    """E190's rows: the insertion study's ``count`` re-splits of the frozen pool at k = 5, each threshold's grid
    committed once for the whole pool."""
    _, halves, cal, levels = resplit_levels(pool_dir, alpha, count, seed)
    by_level = {t: grid_sums(cal, {SHARE_BUDGET: t}) for t in sorted(set(levels))}
    rng = np.random.default_rng(SHARE_SEED)
    rows = [row for n, ((half, held), t) in enumerate(zip(halves, levels))
            for row in split_rows(by_level[t], n, half, held, t, rng, draws)]
    return pd.DataFrame(rows)


def table_rows(cal_dir: Any, test_dir: Any, alpha: float, budgets: Sequence[int], resamples: int, seed: int,
               draws: int = TABLE_DRAWS) -> pd.DataFrame:
    """E191's rows: the random calibration's selected gamma without noise (``draw`` -1) and under ``draws``
    fresh-episode draws (part ``select``), and Table III's calibrated cells at their median (part ``cells``, E82's
    computation with the margin grid {median})."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex9_calibration import margin_rows

    cal_run, test_run = load_run(cal_dir), load_run(test_dir)
    cal, scores = loaded(cal_run, budgets)
    sums = grid_sums(cal, budget_thresholds(scores, alpha, budgets))
    rows, rng = np.arange(len(sums.ids)), np.random.default_rng(TABLE_SEED)
    picked = [select(sums, rows, None if d < 0 else draw_repeats(rng, sums, len(rows))) for d in range(-1, draws)]
    chosen = pd.DataFrame({"part": "select", "draw": np.arange(-1, draws), "index": np.arange(-1, draws),
                           "gamma": [sums.gammas[m] for m, _ in picked], "cal_drawn": [e for _, e in picked]})
    median = float(np.sort(chosen.loc[chosen["draw"] >= 0, "gamma"].to_numpy())[draws // 2])
    del cal, sums
    cells = margin_rows(cal_run, test_run, alpha, budgets, resamples, seed, gamma=median).assign(part="cells")
    return pd.concat([chosen, cells], ignore_index=True)


# ----------------------------------------------------------------------------- keys


def share_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E190's keys (``share.``): the optimistic share, mean gamma, and the mean calibration (as drawn, stored) and
    held-out optimism at the stop, under the draws and without noise (``_plain``); the per-split share's range;
    ``holds`` by the declared rule."""
    from probecommit.studies.paper_values import value

    noisy, plain = rows[rows["draw"] >= 0], rows[rows["draw"] < 0]
    out = {"splits": float(plain["index"].nunique()), "draws": float(noisy["draw"].nunique())}
    for tag, part in (("", noisy), ("_plain", plain)):
        out.update({f"share{tag}": float(part["optimistic"].mean()), f"gamma{tag}": float(part["gamma"].mean()),
                    f"cal_drawn{tag}": float(part["cal_drawn"].mean()), f"cal_true{tag}": float(part["cal_true"].mean()),
                    f"held{tag}": float(part["held"].mean())})
    per = noisy.groupby("index")["optimistic"].mean()
    out["split_share_min"], out["split_share_max"] = float(per.min()), float(per.max())
    paper = float(value("T14-resplits.margin_optimistic_percent")) / 100.0
    out["holds"] = float(abs(out["share"] - paper) <= SHARE_TOL)
    return out


def table_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E191's keys (``table.``): the gamma without noise, the draws' median, min and max, each budget's calibrated
    optimism and interval at the median, and ``holds`` by the declared rule."""
    chosen, cells = rows[rows["part"] == "select"], rows[rows["part"] == "cells"]
    drawn = np.sort(chosen.loc[chosen["draw"] >= 0, "gamma"].to_numpy())
    out = {"gamma_plain": float(chosen.loc[chosen["draw"] < 0, "gamma"].iloc[0]), "draws": float(len(drawn)),
           "gamma_median": float(drawn[len(drawn) // 2]), "gamma_min": float(drawn[0]), "gamma_max": float(drawn[-1])}
    for r in cells.to_dict("records"):
        k = int(r["k"])
        out.update({f"optimism.k{k}": float(r["optimism"]), f"optimism.k{k}.lo": float(r["lo"]),
                    f"optimism.k{k}.hi": float(r["hi"])})
    out["holds"] = table_holds(out)
    return out


def table_holds(keys: dict[str, float]) -> float:
    """1.0 when the paper's calibrated optimism at each of :data:`TABLE_K` lies inside the interval the keys
    ``optimism.k<k>.lo`` / ``.hi`` give (E191's rule; E200's too)."""
    from probecommit.studies.paper_values import value

    return float(all(keys[f"optimism.k{k}.lo"] <= float(value(f"tab:audit.optimism_calibrated.{k}"))
                     <= keys[f"optimism.k{k}.hi"] for k in TABLE_K))


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """Every key of the group from the stored rows (the step and verify both call this)."""
    out: dict[str, float] = {}
    share = rows[rows["part"] == "share"]
    if len(share):
        out.update({f"share.{k}": v for k, v in share_keys(share).items()})
    if (rows["part"] == "select").any():
        out.update({f"table.{k}": v for k, v in table_keys(rows[rows["part"].isin(["select", "cells"])]).items()})
    return out


def compute(ins: Any, alpha: float, count: int, seed: int, budgets: Sequence[int], resamples: int,
            boot_seed: int, share: Any = None, table: Any = None) -> pd.DataFrame:
    """Both experiments' rows from the insertion study's runs folder ``ins`` (run in a process of its own):
    ``share(pool, alpha, count, seed)`` on the frozen pool and ``table(cal, test, alpha, budgets, resamples,
    boot_seed)`` on Table III's random runs (this module's ``share_rows`` and ``table_rows`` unless given: ex33's
    step passes its own)."""
    share, table = share or share_rows, table or table_rows
    return pd.concat([share(ins / POOL, alpha, count, seed),
                      table(ins / TABLE_CAL, ins / TABLE_TEST, alpha, budgets, resamples, boot_seed)],
                     ignore_index=True)


def run(job: Any) -> None:
    """The explain step (set aside to a process of its own): E190's and E191's rows and keys."""
    job.progress("explain: the margin judged on fresh calibration episodes (E190, E191)", 0, 1)
    resamples = int(job.cfg["ex9_cost_resamples_quick" if job.quick else "ex9_cost_resamples"])
    store_rows(job, compute, summary, STORED, GROUP, resamples, int(job.p.bootstrap.seed))


def store_rows(job: Any, compute: Any, summary: Any, stored: str, group: str, resamples: int, boot_seed: int) -> None:
    """An insertion-runs step's rows (``compute`` with the insertion study's alpha, re-splits and random budgets)
    stored as ``stored`` and their ``summary`` in ``group`` (ex30's and ex33's steps)."""
    p = job.p
    rows = compute(job.ins, p.alpha, int(p.resplits["count"]), int(p.resplits["seed"]),
                   list(job.cfg["random_budgets"]), resamples, boot_seed)
    job.stored[stored] = rows
    job.res[group].update(summary(rows))


__all__: Sequence[str] = ("run", "compute", "summary", "share_rows", "table_rows", "share_keys", "table_keys",
                          "GridSums", "grid_sums", "select", "rule_stop", "resplit_levels", "store_rows", "table_holds", "split_rows", "draw_repeats")
