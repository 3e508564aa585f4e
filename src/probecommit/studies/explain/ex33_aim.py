"""The margin items under execution noise on the committed aim (E199, E200; ex33, issue #36; rules declared in
``docs/decisions.md``, "ex33", before any of their numbers were computed).

Why: our insertion outcome is a deterministic engine query of truth and aim, so the realized failure the margin is
fitted to is exactly what the committed aims earn. A robot places the peg where it aims only up to a placement error,
which the model's predicted failure does not include: realized failure rises against predicted at every gamma, the
realized curve is smoothed, and each execution's outcome is a draw. The paper reports no such error, so its size is
declared from the one noise scale it reports, the probe noise sigma = 0.5 mm (:data:`SIGMA`).

MuJoCo's capture edge is the model's ``w(c) = 0.6 c + 1.1`` (within 0.006 mm on every stored peg query of these runs,
decisions.md), so a committed aim ``a`` fails under the error with the analytic probability
:func:`failure_probability`, and no engine is rerun: every aim is a stored commit's (the stored probes recommitted at
each threshold and gamma). E199 draws each execution's outcome (Bernoulli of that probability, independently for every
calibration episode at every candidate gamma and every held-out episode at the stop) over T14's 50 re-splits of the
frozen pool at k = 5; E200 runs the paper's margin rule on the noise-averaged failure of Table III's random
calibration and computes Table III's calibrated cells on the test run with each episode's failure probability. Every
key is :func:`summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.margin import GAMMA_GRID, margin_candidates
from probecommit.studies.explain.ex30_fresh import COLUMNS, SHARE_BUDGET, SHARE_TOL
from probecommit.studies.explain.ex30_fresh import compute as ex30_compute
from probecommit.studies.explain.ex30_fresh import loaded, resplit_levels, rule_stop, store_rows, table_holds
from probecommit.tasks.insertion.model import capture_half_width

#: The stored rows, beside results.json.
STORED = "ex33_aim_rows.parquet"
#: Result group.
GROUP = "ex33_aim"
#: The declared SD of the placement error (mm): the paper's probe noise sigma.
SIGMA = 0.5
#: SDs published beside the rule, noise averaged (mm; 0 is the check: the stored realized failure).
BESIDE = (0.0, 0.1, 0.25)
#: Outcome draws per re-split (E199) and their declared seed.
SHARE_DRAWS, SHARE_SEED = 20, 199
#: Key tag of each SD (the rule's own has none).
TAGS = {0.0: "plain", 0.1: "s010", 0.25: "s025", SIGMA: ""}


def failure_probability(aim: np.ndarray, x_hole: np.ndarray, c: np.ndarray, sigma: float) -> np.ndarray:
    """Probability that an aim at ``aim`` fails when the peg lands at ``aim + eps``, ``eps ~ N(0, sigma^2)``: the
    landing point outside the open capture window ``x_hole +- w(c)`` (``sigma`` 0: the window test itself)."""
    from scipy.stats import norm

    aim, x_hole = np.asarray(aim, dtype=float), np.asarray(x_hole, dtype=float)
    w = capture_half_width(c)
    if sigma == 0:
        return (np.abs(aim - x_hole) >= w).astype(float)
    return norm.sf((x_hole + w - aim) / sigma) + norm.cdf((x_hole - w - aim) / sigma)


class AimGrid:
    """Every candidate gamma's commit of one run's episodes on a fixed episode axis (gammas x episodes): the ok
    mask, predicted failure, the stored realized failure and the committed aim, with each episode's truth."""

    def __init__(self, gammas: list[float], tables: Sequence[pd.DataFrame], truths: pd.DataFrame) -> None:
        every = pd.concat([t.assign(gamma=g) for g, t in zip(gammas, tables)], ignore_index=True)
        episodes = every[["instance_id", "repeat", "k"]].drop_duplicates().sort_values(["instance_id", "repeat", "k"])
        self.gammas = list(gammas)
        self.episodes = episodes.reset_index(drop=True)
        position = pd.Series(np.arange(len(episodes)), index=pd.MultiIndex.from_frame(episodes))
        col = position.loc[pd.MultiIndex.from_frame(every[["instance_id", "repeat", "k"]])].to_numpy()
        row = every["gamma"].map({g: m for m, g in enumerate(self.gammas)}).to_numpy()
        shape = (len(self.gammas), len(episodes))
        ok = every["status"].astype(str).eq("ok").to_numpy()
        self.ok, self.p, self.r, self.aim = (np.zeros(shape) for _ in range(4))
        for target, values in ((self.ok, ok), (self.p, every["predicted"]), (self.r, every["realized"]),
                               (self.aim, every["action"])):
            target[row[ok], col[ok]] = np.asarray(values, dtype=float)[ok]
        truth = truths.loc[self.episodes["instance_id"]]
        self.x, self.c = truth["true_x_hole"].to_numpy(float), truth["true_c"].to_numpy(float)

    def q(self, sigma: float) -> np.ndarray:
        """Each ok episode's failure probability under the placement error (0 where not ok); ``sigma`` 0: the
        stored realized failure (the check)."""
        if sigma == 0:
            return self.r
        return failure_probability(self.aim, self.x[None, :], self.c[None, :], sigma) * self.ok

    def member(self, ids: np.ndarray) -> np.ndarray:
        """Which episodes belong to the instances ``ids`` (bool over the episode axis)."""
        return self.episodes["instance_id"].isin(set(np.asarray(ids).tolist())).to_numpy()


def truths_of(run: Any) -> pd.DataFrame:
    """A loaded run's truths by instance id."""
    return run.instances.set_index("instance_id")[["true_x_hole", "true_c"]]


def aim_grid(cal: Any, thresholds: dict[int, float], truths: pd.DataFrame) -> AimGrid:
    """Every grid gamma's commit of ``cal`` under ``{k: t_k}``, aims kept."""
    gammas = margin_candidates(GAMMA_GRID)
    columns = [(*COLUMNS, "action")] * len(gammas)
    return AimGrid(gammas, cal.commit(*[(dict(thresholds), g) for g in gammas], keep=columns), truths)


def stop_rows(grid: AimGrid, cal: np.ndarray, held: np.ndarray, realized: np.ndarray) -> dict[str, float]:
    """The paper's rule on the ``cal`` episodes given each candidate's ``realized`` failure (gammas x episodes),
    and the calibration and held-out halves' mean optimism at the stop."""
    p, ok = grid.p, grid.ok
    m = rule_stop(grid.gammas, (p * cal).sum(axis=1), (realized * cal).sum(axis=1))

    def optimism(mask: np.ndarray) -> float:
        return float(((realized[m] - p[m]) * mask).sum() / (ok[m] * mask).sum())

    held_e = optimism(held)
    return {"gamma": grid.gammas[m], "cal": optimism(cal), "held": held_e, "optimistic": float(held_e > 0)}


def split_rows(grid: AimGrid, n: int, cal_ids: np.ndarray, held_ids: np.ndarray, level: float,
               rng: np.random.Generator, draws: int) -> list[dict[str, Any]]:
    """One re-split's rows: noise averaged at every SD (mode ``mean``; SD 0 the stored outcomes) and ``draws``
    sampled-outcome draws at :data:`SIGMA` (mode ``drawn``; each a fresh uniform per gamma and episode)."""
    cal, held = grid.member(cal_ids), grid.member(held_ids)
    base = {"part": "share", "index": n, "level": level}
    out = [{**base, "mode": "mean", "sigma": s, "draw": -1, **stop_rows(grid, cal, held, grid.q(s))}
           for s in (*BESIDE, SIGMA)]
    q = grid.q(SIGMA)
    for d in range(draws):
        drawn = (rng.random(q.shape) < q).astype(float)
        out.append({**base, "mode": "drawn", "sigma": SIGMA, "draw": d, **stop_rows(grid, cal, held, drawn)})
    return out


def share_rows(pool_dir: Any, alpha: float, count: int, seed: int, draws: int = SHARE_DRAWS) -> pd.DataFrame:
    """E199's rows: the insertion study's ``count`` re-splits of the frozen pool at k = 5, each threshold's grid
    committed once for the whole pool."""
    pool, halves, cal, levels = resplit_levels(pool_dir, alpha, count, seed)
    truths = truths_of(pool)
    by_level = {t: aim_grid(cal, {SHARE_BUDGET: t}, truths) for t in sorted(set(levels))}
    rng = np.random.default_rng(SHARE_SEED)
    return pd.DataFrame([row for n, ((half, held), t) in enumerate(zip(halves, levels))
                         for row in split_rows(by_level[t], n, half, held, t, rng, draws)])


def cells(table: pd.DataFrame, truths: pd.DataFrame, gamma: float, sigma: float, budgets: Sequence[int],
          resamples: int, seed: int) -> pd.DataFrame:
    """Table III's calibrated cells from the test run's ``table`` committed at ``(t_k, gamma)``, each ok episode's
    realized failure replaced by its failure probability under the placement error (``sigma`` 0: the stored
    outcomes), computed as Table III computes them (``audit.metrics.audit_table``)."""
    from probecommit.audit.metrics import audit_table

    if sigma > 0:
        ok = table["status"].astype(str).eq("ok").to_numpy()
        t = truths.loc[table["instance_id"]]
        q = failure_probability(table["action"].to_numpy(float), t["true_x_hole"].to_numpy(float),
                                t["true_c"].to_numpy(float), sigma)
        table = table.assign(realized=np.where(ok, q, table["realized"].to_numpy(float)))
    audit = audit_table(table, budgets=list(budgets), resamples=resamples, seed=seed)
    return pd.DataFrame({"part": "cells", "sigma": sigma, "gamma": gamma, "k": audit["k"].astype(int).to_numpy(),
                         "optimism": audit["optimism"].to_numpy(float), "lo": audit["optimism_lo"].to_numpy(float),
                         "hi": audit["optimism_hi"].to_numpy(float)})


def table_rows(cal_dir: Any, test_dir: Any, alpha: float, budgets: Sequence[int], resamples: int,
               seed: int) -> pd.DataFrame:
    """E200's rows: at every SD, the random calibration's margin by the paper's rule on the noise-averaged failure
    and Table III's calibrated cells on the test run at it (one row per SD and budget)."""
    from probecommit.audit.conformal import budget_thresholds
    from probecommit.runner.replay import load_run

    cal_run, test_run = load_run(cal_dir), load_run(test_dir)
    cal, scores = loaded(cal_run, budgets)
    thresholds = budget_thresholds(scores, alpha, budgets)
    grid = aim_grid(cal, thresholds, truths_of(cal_run))
    chosen = {s: grid.gammas[rule_stop(grid.gammas, grid.p.sum(axis=1), grid.q(s).sum(axis=1))]
              for s in (*BESIDE, SIGMA)}
    del cal, grid
    test, _ = loaded(test_run, budgets)
    distinct = sorted(set(chosen.values()), reverse=True)  # each selected gamma's test commit made once
    tables = dict(zip(distinct, test.commit(*[(dict(thresholds), g) for g in distinct])))
    truths = truths_of(test_run)
    return pd.concat([cells(tables[g], truths, g, s, budgets, resamples, seed) for s, g in chosen.items()],
                     ignore_index=True)


# ----------------------------------------------------------------------------- keys


def _tag(sigma: float, name: str) -> str:
    """A key name at the SD ``sigma`` (the rule's own SD untagged)."""
    tag = TAGS[round(float(sigma), 10)]
    return f"{tag}.{name}" if tag else name


def share_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E199's keys (``share.``): the optimistic share, mean gamma and the halves' mean optimism at the stop, under
    the sampled outcomes and noise averaged at every SD (tagged); ``holds`` by the declared rule."""
    from probecommit.studies.paper_values import value

    drawn, mean = rows[rows["mode"] == "drawn"], rows[rows["mode"] == "mean"]
    out = {"splits": float(rows["index"].nunique()), "draws": float(drawn["draw"].nunique()), "sigma": SIGMA}
    parts = [("", drawn)] + [(f"{_tag(s, 'mean')}_", part) for s, part in mean.groupby("sigma")]
    for prefix, part in parts:
        out.update({f"{prefix}{name}": float(part[column].mean()) for name, column in
                    (("share", "optimistic"), ("gamma", "gamma"), ("cal", "cal"), ("held", "held"))})
    paper = float(value("T14-resplits.margin_optimistic_percent")) / 100.0
    out["holds"] = float(abs(out["share"] - paper) <= SHARE_TOL)
    return out


def table_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E200's keys (``table.``): at every SD (tagged), the selected gamma and each budget's calibrated optimism
    with its interval; ``holds`` by the declared rule (the rule's SD, E191's test)."""
    out: dict[str, float] = {"sigma": SIGMA}
    for r in rows.to_dict("records"):
        k = int(r["k"])
        out[_tag(r["sigma"], "gamma")] = float(r["gamma"])
        out.update({_tag(r["sigma"], f"optimism.k{k}{x}"): float(r[c]) for x, c in (("", "optimism"), (".lo", "lo"),
                                                                                        (".hi", "hi"))})
    out["holds"] = table_holds(out)
    return out


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """Every key of the group from the stored rows (the step and verify both call this)."""
    out: dict[str, float] = {}
    for part, keys in (("share", share_keys), ("cells", table_keys)):
        sub = rows[rows["part"] == part]
        if len(sub):
            out.update({f"{'share' if part == 'share' else 'table'}.{k}": v for k, v in keys(sub).items()})
    return out


def compute(ins: Any, alpha: float, count: int, seed: int, budgets: Sequence[int], resamples: int,
            boot_seed: int) -> pd.DataFrame:
    """Both experiments' rows from the insertion study's runs folder ``ins`` (run in a process of its own)."""
    return ex30_compute(ins, alpha, count, seed, budgets, resamples, boot_seed, share_rows, table_rows)


def run(job: Any) -> None:
    """The explain step (set aside to a process of its own): E199's and E200's rows and keys, E200's bootstrap
    Table III's own (the insertion study's resamples and seed)."""
    job.progress("explain: the margin items under execution noise on the aim (E199, E200)", 0, 1)
    store_rows(job, compute, summary, STORED, GROUP, int(job.p.bootstrap.resamples), int(job.p.bootstrap.seed))


__all__: Sequence[str] = ("run", "compute", "summary", "share_rows", "table_rows", "share_keys", "table_keys", "cells",
                          "AimGrid", "aim_grid", "failure_probability", "split_rows", "stop_rows", "truths_of")
