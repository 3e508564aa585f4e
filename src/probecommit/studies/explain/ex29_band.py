"""T36's k = 1 AUC at the first-tap band loss the paper's own k = 1 escape implies (E187; ex29, issue #36; rule
declared in ``docs/decisions.md``, "ex29").

Why: at k = 1 the belief is the prior, so a cover trajectory's running-max surprise is, up to its reading's noise,
whether the first tap read the pocket, and the k = 1 AUC counts how many final-budget escapes come from the first
tap's misread band (E127: the paper's 0.85 needs most of that band still escaped at k = 5). The paper does report
what its filter does to a first tap's band: random-probe k = 1 escape 0.055, all of it from the first tap's band, so
its filter loses q1 = 0.055 / P(band) of the band at the first tap, and later cover taps keep what it lost (E150's
trace). This step reweights each paper's-schedule draw so that its band's escaped share is q1 and reads the weighted
k = 1 AUC. Beside it, on the claim's own run (our schedule), why our AUC is below chance (the first tap's pocket
reading falls on covered trajectories), and on Table III's random run the band loss at the cover schedule's first
tap against all positions. It reads stored episode tables only; every key is :func:`summary` of its rows.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

#: The stored rows (one per trajectory of every part), beside results.json.
STORED = "ex29_band_rows.parquet"
#: Result group.
GROUP = "ex29_band"
#: E106's five paper's-schedule draws, in its order; then the claim's own run and Table III's random test run.
DRAWS = ("b_test", "b_cal", "a", "pool_0", "pool_1")
OURS, RANDOM = "ours", "random"
#: The band's inputs, stored on every row (a closed form of the runs' config).
BAND_COLUMNS = ("x_low", "x_high", "c_low", "c_high", "tip_radius", "sim_offset")


def part_rows(part: str, episodes: pd.DataFrame, probes: pd.DataFrame, instances: pd.DataFrame, label_k: int,
              inputs: Mapping[str, float]) -> pd.DataFrame:
    """One row per trajectory of one run (or half of one): the stored k = 1 running-max surprise, escape outside
    the full hull at ``label_k`` (``escaped_final``), whether the first tap read the pocket, the first tap's
    position and whether the truth lies in its misread band (``ex13_surprise.draw_rows`` plus the truths)."""
    from probecommit.studies.explain.ex13_surprise import draw_rows
    from probecommit.studies.explain.ex14_escape import in_band
    from probecommit.studies.explain.surprise_variants import POCKET_CUT_MM
    from probecommit.tasks.insertion.model import half_gap

    rows = draw_rows(part, episodes, probes, 1, label_k, POCKET_CUT_MM)
    rows = rows[["draw", "instance_id", "repeat", "surprise_k1", "escaped_final", "first_tap_pocket"]]
    rows = rows.rename(columns={"draw": "part"})
    key = ["instance_id", "repeat"]
    first = probes.loc[probes["j"] == 1, [*key, "u"]].astype({"instance_id": str, "repeat": "int64"})
    truths = instances[["instance_id", "true_x_hole", "true_c"]].astype({"instance_id": str})
    rows = rows.merge(first, on=key, how="left", validate="one_to_one").merge(
        truths.drop_duplicates("instance_id"), on="instance_id", how="left", validate="many_to_one")
    band = in_band(rows["u"].to_numpy(float), rows["true_x_hole"].to_numpy(float),
                   half_gap(rows["true_c"].to_numpy(float)), -inputs["tip_radius"], inputs["sim_offset"])
    return rows.drop(columns=["true_x_hole", "true_c"]).rename(columns={"u": "first_tap"}).assign(
        in_band=np.asarray(band, bool), **dict(inputs))


def band_weights(part: pd.DataFrame, q: float) -> np.ndarray | None:
    """Weights that set the band's escaped share to ``q``: escaped band trajectories ``q / s``, covered band ones
    ``(1 - q) / (1 - s)`` (``s`` the part's own share), the rest 1; None when ``s`` is 0 or 1 (or no band)."""
    band, esc = part["in_band"].to_numpy(bool), part["escaped_final"].to_numpy(bool)
    if not band.any():
        return None
    s = float(esc[band].mean())
    if not 0.0 < s < 1.0:
        return None
    return np.where(band & esc, q / s, np.where(band, (1.0 - q) / (1.0 - s), 1.0))


def band_weighted_auc(part: pd.DataFrame, q: float | None) -> float:
    """The weighted Mann-Whitney AUC of the k = 1 surprise for final-budget escape at band loss ``q`` (None: the
    part as it is)."""
    from probecommit.studies.explain.ex24_band import weighted_auc

    w = np.ones(len(part)) if q is None else band_weights(part, q)
    if w is None:
        return float("nan")
    return weighted_auc(part["surprise_k1"].to_numpy(float), part["escaped_final"].to_numpy(bool), w)


def _p_band(b: pd.Series, taps: Sequence[float]) -> float:
    from probecommit.studies.explain.ex14_escape import p_band
    from probecommit.tasks.insertion.model import half_gap

    return p_band(list(taps), (float(b["x_low"]), float(b["x_high"])), (float(b["c_low"]), float(b["c_high"])),
                  half_gap, -float(b["tip_radius"]), float(b["sim_offset"]))


def rates(rows: pd.DataFrame) -> dict[str, float]:
    """The band losses the keys read: ``p_band_nine`` (a first tap uniform over the probe grid), ``q1`` (the
    paper's k = 1 escape over it: E112's implied P(escape | band)), ``p_band_first`` (the paper's schedule's first
    tap), ``implied`` (E127's least band share the paper's k = 1 AUC needs) and ``top_first_room`` (the most escapes
    that may read top first under a binary first reading with the paper's AUC and escapes: FPR >= 0 gives
    TPR >= 2 AUC - 1)."""
    from probecommit.studies.explain.ex17 import paper_t36
    from probecommit.studies.explain.ex17_band import implied_share
    from probecommit.studies.paper_values import value
    from probecommit.tasks.insertion.model import InsertionModel

    draws = rows[rows["part"].isin(DRAWS)]
    b = draws.iloc[0]
    nine = _p_band(b, InsertionModel.probe_grid[:, 0])
    first = _p_band(b, [float(b["first_tap"])])
    n, escaped, auc = paper_t36()
    return {"p_band_nine": nine, "q1": value("T11-audit-trend.escape_k1") / 100.0 / nine, "p_band_first": first,
            "first_tap": float(b["first_tap"]), "implied": implied_share(first, n, escaped, auc),
            "top_first_room": 2.0 * (1.0 - auc) * escaped}


def _span(out: dict[str, Any], name: str, values: list[float]) -> None:
    finite = [v for v in values if np.isfinite(v)]
    out[f"{name}.min"], out[f"{name}.max"] = (min(finite), max(finite)) if finite else (float("nan"),) * 2


def draw_keys(rows: pd.DataFrame, q: Mapping[str, float]) -> dict[str, Any]:
    """Per paper's-schedule draw: counts, the band's escaped share, the escapes that read top first, and the k = 1
    AUC as it is (``auc``), at ``q1`` (``auc_q1``: the rule's), at 1 (``auc_all``) and at E127's implied share
    (``auc_implied``); each one's span over the draws; ``holds``, E187's rule."""
    from probecommit.studies.paper_values import value

    out: dict[str, Any] = {}
    names = [d for d in DRAWS if d in set(rows["part"])]
    spans: dict[str, list[float]] = {n: [] for n in ("auc", "auc_q1", "auc_all", "auc_implied", "band_share",
                                                    "top_first_escapes")}
    for d in names:
        part = rows[rows["part"] == d]
        band, esc = part["in_band"].to_numpy(bool), part["escaped_final"].to_numpy(bool)
        top = ~part["first_tap_pocket"].to_numpy(bool)
        got = {"band_share": float(esc[band].mean()) if band.any() else float("nan"),
               "top_first_escapes": float((esc & top).sum()), "auc": band_weighted_auc(part, None),
               "auc_q1": band_weighted_auc(part, q["q1"]), "auc_all": band_weighted_auc(part, 1.0),
               "auc_implied": band_weighted_auc(part, min(q["implied"], 1.0))}
        out.update({f"{d}.n": int(len(part)), f"{d}.n_escaped": int(esc.sum()), f"{d}.n_band": int(band.sum()),
                    f"{d}.n_band_escaped": int((band & esc).sum())})
        for name, v in got.items():
            out[f"{d}.{name}"] = v
            spans[name].append(v)
    out["draws"] = len(names)
    for name, values in spans.items():
        _span(out, name, values)
    paper = value("T36-surprise.auc_k1")
    out["holds"] = float(bool(names) and out["auc_q1.min"] <= paper <= out["auc_q1.max"])
    return out


def ours_keys(part: pd.DataFrame) -> dict[str, Any]:
    """The claim's own run: its first tap, TPR and FPR of the first tap's pocket reading, the binary value
    0.5 + (TPR - FPR) / 2, the stored surprise's AUC and the escapes in the first tap's band."""
    esc, pocket = part["escaped_final"].to_numpy(bool), part["first_tap_pocket"].to_numpy(bool)
    band = part["in_band"].to_numpy(bool)
    tpr = float(pocket[esc].mean()) if esc.any() else float("nan")
    fpr = float(pocket[~esc].mean()) if (~esc).any() else float("nan")
    return {"first_tap": float(part["first_tap"].iloc[0]), "n": int(len(part)), "n_escaped": int(esc.sum()),
            "tpr": tpr, "fpr": fpr, "binary": 0.5 + (tpr - fpr) / 2.0, "auc": band_weighted_auc(part, None),
            "n_band": int(band.sum()), "band_escapes": int((band & esc).sum())}


def random_keys(part: pd.DataFrame, first_tap: float) -> dict[str, Any]:
    """Table III's random run at k = 1: the escaped share of first-tap band trajectories whose first tap was at
    the cover schedule's first tap (``at_first``) and over all positions (``all``), their counts, and the escapes
    off the band."""
    band, esc = part["in_band"].to_numpy(bool), part["escaped_final"].to_numpy(bool)
    at = np.isclose(part["first_tap"].to_numpy(float), first_tap)
    share = lambda sel: float(esc[sel].mean()) if sel.any() else float("nan")  # noqa: E731
    return {"n_band.at_first": int((band & at).sum()), "n_band.all": int(band.sum()),
            "band_escaped_k1.at_first": share(band & at), "band_escaped_k1.all": share(band),
            "escaped_k1_off_band": int((esc & ~band).sum())}


def position_keys(rows: pd.DataFrame, q1: float, random_all: float) -> dict[str, Any]:
    """Whether the first tap's position loses its band at the average rate q1 stands for (no rule reads these):
    the draws' pooled band escaped share at the final budget (``band_share.pooled``; the band's hull is the same
    at k = 1 on nearly all of them, E150's trace), its ratio to the random run's share over all positions (``position_ratio``),
    ``q_first`` = q1 times that ratio, and the draws' k = 1 AUCs at ``q_first`` (``auc_q_first.{min,max}``)."""
    draws = rows[rows["part"].isin(DRAWS)]
    band = draws["in_band"].to_numpy(bool)
    pooled = float(draws["escaped_final"].to_numpy(bool)[band].mean()) if band.any() else float("nan")
    ratio = pooled / random_all if random_all > 0 else float("nan")
    out: dict[str, Any] = {"band_share.pooled": pooled, "position_ratio": ratio, "q_first": q1 * ratio}
    values = [band_weighted_auc(draws[draws["part"] == d], min(q1 * ratio, 1.0)) if np.isfinite(ratio)
              else float("nan") for d in DRAWS if d in set(draws["part"])]
    _span(out, "auc_q_first", values)
    return out


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """E187's keys from the stored rows: :func:`rates`, :func:`draw_keys`, ``ours.`` (:func:`ours_keys`) and
    ``random.`` (:func:`random_keys`), the last two when their rows are stored, and with the random run
    :func:`position_keys`."""
    q = rates(rows)
    out: dict[str, Any] = dict(q)
    out.update(draw_keys(rows, q))
    for name, keys in ((OURS, ours_keys), (RANDOM, lambda p: random_keys(p, q["first_tap"]))):
        part = rows[rows["part"] == name]
        if len(part):
            out.update({f"{name}.{k}": v for k, v in keys(part).items()})
    if f"{RANDOM}.band_escaped_k1.all" in out:
        out.update(position_keys(rows, q["q1"], out[f"{RANDOM}.band_escaped_k1.all"]))
    return out


def _inputs(loaded: Any) -> dict[str, float]:
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM

    m = loaded.config.model
    return {"x_low": float(m.prior_low[0]), "x_high": float(m.prior_high[0]), "c_low": float(m.prior_low[1]),
            "c_high": float(m.prior_high[1]), "tip_radius": TIP_RADIUS_MM,
            "sim_offset": float(loaded.config.simulator.boundary_offset)}


def run(job: Any) -> None:
    """The explain step (set aside: it loads six stored runs): E106's draws, the claim's cover run and Table III's
    random test run, read as stored (about a second)."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex13 import POOL_RUN
    from probecommit.studies.explain.ex13_surprise import pool_halves
    from probecommit.studies.explain.ex21 import PAPER_RUNS

    job.progress("explain: T36's k = 1 AUC at the paper's own first-tap band loss (E187)", 0, 1)
    k = int(job.p.budgets["cover"])
    test = load_run(job.runs / PAPER_RUNS["test"])
    inputs = _inputs(test)
    named = {"b_test": test, "b_cal": load_run(job.runs / PAPER_RUNS["cal"]), "a": load_run(job.runs / PAPER_RUNS["A"])}
    parts = [part_rows(d, r.episodes, r.probes, r.instances, k, inputs) for d, r in named.items()]
    if (job.runs / POOL_RUN / "episodes.parquet").is_file():
        pool = load_run(job.runs / POOL_RUN)
        parts += [part_rows(f"pool_{i}", e, p, pool.instances, k, inputs)
                  for i, (e, p) in enumerate(pool_halves(pool.episodes, pool.probes, pool.instances))]
    for name, run_name, label_k in ((OURS, "B_test_cover", k), (RANDOM, "B_test_random", 1)):
        r = job.load(run_name)
        parts.append(part_rows(name, r.episodes, r.probes, r.instances, label_k, inputs))
    rows = pd.concat(parts, ignore_index=True)
    job.stored[STORED] = rows
    job.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "part_rows", "band_weights", "band_weighted_auc", "rates", "draw_keys",
                          "ours_keys", "random_keys", "position_keys")
