"""T36's k = 1 AUC with the first tap's jitter tail removed alone, the jitter read as a variance, and the draws
post-stratified to the band's design exposure (E168, E169, E170; docs/decisions.md, "ex24").

Why: E151 removed the jitter of each trajectory's FIRST resampling; the first tap's band truths then stayed lost as
the paper's k = 1 AUC needs, but other truths were lost too, diluting the AUC. A trajectory that reads top at -12 mm
first resamples at a later tap, and a truth in THAT tap's misread band is contradicted at 30 sigma just as the first
tap's band truths are. This module replays E106's stored taps (``ex21``'s rows machinery, ``ex21_band._log_space``)
with the jitter removed only at tap 1's resampling, and with the notation's variance reading of the jitter; it
records each trajectory's first resampling tap and whether its truth lies in that tap's band, so E151's escapes can
be split by cause; and it weights each draw's trajectories to the design's exposure to the first tap's band. One row
per trajectory and reading; the keys are summaries of the rows.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Iterator, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex21_band

#: The stated filter (the check), E151's mode (for its decomposition), E168's and E169's modes.
READINGS = ("stated", "first_unjittered", "tap1_unjittered", "variance")
#: The stored rows (one per trajectory, draw and reading).
STORED = "ex24_band_rows.parquet"
#: The first tap's band inputs, stored on every row (a closed form of the runs' config; E170's exposure).
BAND_COLUMNS = ("first_tap", "x_low", "x_high", "c_low", "c_high", "tip_radius", "sim_offset")
#: The readings whose draws E170 post-stratifies (its rule reads ``stated``).
POST_STRATIFIED = ("stated", "tap1_unjittered")


class _TapKernel:
    """A ``jitter_resampled`` kernel told the current tap (``tap``, 1-based): ``tap1_unjittered`` zeroes the noise of
    the copies made at tap 1 (drawn, so later draws are the stated run's), ``variance`` jitters with the square root
    of the stated scale (N(0, v) read as a variance), anything else jitters as stated."""

    def __init__(self, kernel: Any, mode: str) -> None:
        self.kernel, self.mode, self.tap = kernel, mode, 1

    def __call__(self, particles, rows, parents, noise, scale, low, high):
        if self.mode == "tap1_unjittered" and self.tap == 1:
            noise = np.zeros_like(noise)
        if self.mode == "variance":
            scale = np.sqrt(np.asarray(scale, float))
        return self.kernel(particles, rows, parents, noise, scale, low, high)


def taps(pf: Any, reading: str, batch: Any, rngs: Sequence[Any], final_k: int) -> Iterator[tuple]:
    """``ex21_band._log_space``'s per-tap tuples under ``reading`` (``first_unjittered``: E151's own mode)."""
    if reading == "first_unjittered":
        yield from ex21_band._log_space(pf, "first", batch, rngs, final_k)
        return
    kernel = _TapKernel(pf.kernels.jitter_resampled, reading)
    f = replace(pf, kernels=replace(pf.kernels, jitter_resampled=kernel))
    for item in ex21_band._log_space(f, "stated", batch, rngs, final_k):
        yield item
        kernel.tap = int(item[0]) + 1


def tap_bands(u: np.ndarray, x: np.ndarray, hg: np.ndarray, inner: float, outer: float) -> np.ndarray:
    """``[E, K]``: whether each trajectory's truth lies in tap j's misread band (``ex14_escape.in_band``)."""
    from probecommit.studies.explain.ex14_escape import in_band

    u = np.asarray(u, float).reshape(len(x), -1)
    return np.stack([np.asarray(in_band(u[:, j], x, hg, inner, outer), bool) for j in range(u.shape[1])], axis=1)


def trajectory_rows(beliefs: Any, reading: str, final_k: int, band_inner: float, band_outer: float) -> pd.DataFrame:
    """One row per trajectory of ``beliefs`` (a ``RunBeliefs``) under ``reading``: running-max surprise and escape at
    k = 1 and ``final_k``, the first tap's band, the tap of the first resampling (0: none) and whether the truth lies
    in that tap's band (``ex21.rows_of``' ``trajectory_rows``)."""
    from probecommit.runner.seeding import INFERENCE, episode_rngs
    from probecommit.tasks.insertion.model import half_gap

    batch = beliefs.batch.subset(np.flatnonzero(beliefs.batch.status == "ok"))
    pf = beliefs.pfilter
    rngs = episode_rngs(beliefs.config.seed, batch.split, batch.instance_index, batch.repeat, INFERENCE)
    z, e = batch.truths[:, 0], batch.n_episodes
    bands = tap_bands(batch.u[:, :final_k], z, half_gap(batch.truths[:, 1]), band_inner, band_outer)
    running, first = np.full(e, -np.inf), np.zeros(e, dtype=np.int64)
    out: dict[str, Any] = {}
    for k, particles, resampled, surprise, _copies, _every in taps(pf, reading, batch, rngs, final_k):
        running = np.maximum(running, surprise)
        first = np.where((first == 0) & np.asarray(resampled, bool), k, first)
        escaped = (z < particles[:, :, 0].min(axis=1)) | (z > particles[:, :, 0].max(axis=1))
        if k == 1:
            out.update(surprise_k1=running.copy(), escaped_k1=escaped)
        if k == final_k:
            out.update(surprise_final=running.copy(), escaped_final=escaped)
    at_first = np.where(first > 0, bands[np.arange(e), np.maximum(first, 1) - 1], False)
    return pd.DataFrame({"reading": reading, "instance_id": batch.instance_id.astype(str),
                         "repeat": batch.repeat.astype("int64"), "in_band": bands[:, 0],
                         "first_resample_tap": first, "band_at_first_resample": at_first, **out})


def weighted_auc(score: np.ndarray, positive: np.ndarray, weight: np.ndarray) -> float:
    """The weighted Mann-Whitney AUC: sum over (positive i, negative j) of w_i w_j ([s_i > s_j] + [s_i = s_j] / 2),
    over (sum of positive weights)(sum of negative weights); NaN without both classes."""
    s, y, w = np.asarray(score, float), np.asarray(positive, bool), np.asarray(weight, float)
    neg_s, neg_w = s[~y], w[~y]
    if not y.any() or not len(neg_s):
        return float("nan")
    order = np.argsort(neg_s, kind="stable")
    neg_s, cum = neg_s[order], np.concatenate([[0.0], np.cumsum(neg_w[order])])
    below = cum[np.searchsorted(neg_s, s[y], side="left")]
    upto = cum[np.searchsorted(neg_s, s[y], side="right")]
    return float(np.sum(w[y] * (below + 0.5 * (upto - below))) / (w[y].sum() * neg_w.sum()))


def post_stratified_auc(part: pd.DataFrame, p: float, column: str = "surprise_k1") -> float:
    """The AUC of ``column`` for final-budget escape with band trajectories weighted ``p / p_hat`` and the others
    ``(1 - p) / (1 - p_hat)`` (``p_hat`` the draw's band share): the draw at the design's band exposure ``p``."""
    band = part["in_band"].to_numpy(bool)
    p_hat = float(band.mean()) if len(band) else float("nan")
    if not 0.0 < p_hat < 1.0:
        return float("nan")
    w = np.where(band, p / p_hat, (1.0 - p) / (1.0 - p_hat))
    return weighted_auc(part[column].to_numpy(float), part["escaped_final"].to_numpy(bool), w)


def design_exposure(rows: pd.DataFrame) -> float:
    """The exact P(first tap's band) under the prior box, from the band inputs stored on the rows (E127's)."""
    from probecommit.studies.explain.ex14_escape import p_band
    from probecommit.tasks.insertion.model import half_gap

    b = rows.iloc[0]
    return p_band([float(b["first_tap"])], (float(b["x_low"]), float(b["x_high"])),
                  (float(b["c_low"]), float(b["c_high"])), half_gap, -float(b["tip_radius"]), float(b["sim_offset"]))


def decomposition(part: pd.DataFrame, draws: Sequence[str]) -> dict[str, Any]:
    """Final-budget escapes split by cause, per draw and pooled: the first tap's band, the band of the tap of the
    trajectory's first resampling (not the first tap's), neither."""
    out: dict[str, Any] = {}
    for name, sel in [*((d, part["draw"] == d) for d in draws), ("all", part["draw"].isin(list(draws)))]:
        p = part[sel & part["escaped_final"]]
        band1 = p["in_band"].to_numpy(bool)
        at_first = p["band_at_first_resample"].to_numpy(bool) & ~band1
        out[f"{name}.escapes.band1"], out[f"{name}.escapes.first_resample_band"] = int(band1.sum()), int(at_first.sum())
        out[f"{name}.escapes.other"] = int(len(p) - band1.sum() - at_first.sum())
    return out


def keys(rows: pd.DataFrame, resamples: int, seed: int) -> dict[str, Any]:
    """E168-E170's keys from the stored rows: per reading ``ex21_band.reading_keys`` and :func:`decomposition`; the
    post-stratified k = 1 AUCs with each draw's band exposure; the check that the stated replay gives every stored
    final-budget escape."""
    draws = [d for d in ex21_band.DRAWS if d in set(rows["draw"])]
    p = design_exposure(rows)
    out: dict[str, Any] = {"draws": len(draws), "p_band": p}
    for reading in READINGS:
        part = rows[rows["reading"] == reading]
        out.update({f"{reading}.{k}": v for k, v in ex21_band.reading_keys(part, draws, resamples, seed).items()})
        out.update({f"{reading}.{k}": v for k, v in decomposition(part, draws).items()})
    for reading in POST_STRATIFIED:
        part, values = rows[rows["reading"] == reading], []
        for d in draws:
            values.append(post_stratified_auc(part[part["draw"] == d], p))
            out[f"{reading}.{d}.auc_k1_post"] = values[-1]
        ex21_band._span(out, f"{reading}.auc_k1_post", values)
    stated = rows[rows["reading"] == "stated"]
    for d in draws:
        out[f"{d}.exposure"] = float(stated.loc[stated["draw"] == d, "in_band"].mean())
    ex21_band._span(out, "exposure", [out[f"{d}.exposure"] for d in draws])
    out["stated_reproduces_stored"] = int(bool(len(stated)) and bool(
        (stated["escaped_final"].to_numpy(bool) == stated["stored_escaped_final"].to_numpy(bool)).all()))
    return out
