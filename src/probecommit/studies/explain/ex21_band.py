"""How our filter keeps T36's band truths, under the unstated weight and jitter choices (E150, E151).

Why: T36's k = 1 AUC (paper 0.85) needs nearly every trajectory whose first tap (-12 mm) falls in the misread band
(pocket in the simulator, top in the model) to stay escaped at k = 5 (E127); ours keeps 0.12-0.30. The paper says
"resampling removes the truth". In ours the first tap gives the truth's region a log-weight 450 below the
pocket-consistent particles, systematic resampling makes no copy of it, and the jitter of the copies near the
consistent edge reaches most of the 2.1 mm band; no later cover-schedule tap contradicts that tail. This module
replays stored taps under the readings of what the paper's filter paragraph leaves unstated (docs/decisions.md,
"ex21"): linear-space weights in float64 or float32 (a contradicted weight underflows; a tap contradicting every
particle resets to 1/N), the jitter as the next tap's move, and, removing the suspected cause, the first
resampling's jitter. One row per trajectory and reading; the keys are summaries of the rows.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Sequence

import numpy as np
import pandas as pd

#: W0 (ours), the three readings E150 scans in order, and E151's cause removed.
READINGS = ("stated", "linear64", "linear32", "move_next", "first_unjittered")
#: E150's readings, in the order its rule scans them.
E150_READINGS = ("linear64", "linear32", "move_next")
#: The stored rows (one per trajectory, draw and reading).
STORED = "ex21_band_rows.parquet"


class _Copies:
    """A ``jitter_resampled`` kernel: records each step's copies before their jitter and, by mode, leaves the
    copies of a trajectory's first resampling unjittered (``first``) or every resampling's copies unjittered with
    their noise kept for the next update (``next``); ``stated`` jitters as the filter does."""

    def __init__(self, kernel: Any, mode: str, n_episodes: int) -> None:
        self.kernel, self.mode = kernel, mode
        self.copies: tuple[np.ndarray, np.ndarray] | None = None
        self.done = np.zeros(n_episodes, dtype=bool)
        self.pending: dict[int, np.ndarray] = {}

    def __call__(self, particles, rows, parents, noise, scale, low, high):
        rows = np.asarray(rows)
        new = np.take_along_axis(particles[rows], parents[:, :, None], axis=1)
        self.copies = (rows, new)
        if self.mode == "next":
            out = particles.copy()
            out[rows] = new
            self.pending.update({int(r): noise[i].copy() for i, r in enumerate(rows)})
            return out
        if self.mode == "first":
            noise = np.where(~self.done[rows][:, None, None], 0.0, noise)
        self.done[rows] = True
        return self.kernel(particles, rows, parents, noise, scale, low, high)

    def move(self, particles: np.ndarray, scale, low, high) -> np.ndarray:
        """The pending moves (``next``) applied: jittered and clipped copies, before the next tap reweights."""
        if not self.pending:
            return particles
        out = particles.copy()
        for r, noise in self.pending.items():
            out[r] = np.clip(out[r] + scale * noise, low, high)
        self.pending = {}
        return out


def _box(pf: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    m = pf.model
    return (np.asarray(m.jitter_scale, float), np.asarray(m.prior_low, float), np.asarray(m.prior_high, float))


def _log_space(pf: Any, mode: str, batch: Any, rngs: Sequence[Any], final_k: int):
    """Yield ``(k, particles, resampled, surprise, copies, contradicted_all)`` per tap, ours in log space."""
    copies = _Copies(pf.kernels.jitter_resampled, mode, batch.n_episodes)
    f = replace(pf, kernels=replace(pf.kernels, jitter_resampled=copies))
    state = f.initial(rngs)
    for j in range(final_k):
        if mode == "next":
            state = replace(state, particles=copies.move(state.particles, *_box(pf)), fresh_weights=None)
        every = _contradicted_all(pf, state.particles, batch.u[:, j], batch.y[:, j])
        copies.copies = None
        state = f.update(state, batch.u[:, j], batch.y[:, j], rngs)
        yield j + 1, state.particles, np.asarray(state.resampled, bool), -state.log_evidence, copies.copies, every


def _linear(pf: Any, dtype: Any, batch: Any, rngs: Sequence[Any], final_k: int):
    """The same per tap, weights kept as linear numbers of ``dtype`` (a tap leaving every weight zero: 1/N)."""
    scale, low, high = _box(pf)
    state = pf.initial(rngs)
    particles, n = state.particles, pf.n_particles
    w = np.full(particles.shape[:2], 1.0 / n, dtype=dtype)
    sigma = float(pf.likelihood.sigma)
    log_c = -np.log(sigma * np.sqrt(2.0 * np.pi))
    for j in range(final_k):
        every = _contradicted_all(pf, particles, batch.u[:, j], batch.y[:, j])
        pred = pf.model.predict(np.asarray(batch.u[:, j], float), particles)[..., 0]
        r = -0.5 * np.square((np.asarray(batch.y[:, j], float).reshape(-1, 1) - pred) / sigma)
        w = w * np.exp(r.astype(dtype))
        total = w.sum(axis=1, dtype=dtype)
        with np.errstate(divide="ignore"):
            surprise = -(np.log(total.astype(float)) + log_c)
        dead = total == 0
        w = np.where(dead[:, None], dtype(1.0 / n), w / np.where(dead, 1, total)[:, None]).astype(dtype)
        w64 = w.astype(float)
        resample = 1.0 / np.sum(np.square(w64), axis=1) < pf.resample_fraction * n
        copies = None
        if np.any(resample):
            rows = np.flatnonzero(resample)
            offsets = np.array([rngs[i].random() for i in rows])
            parents = pf.kernels.systematic_resample(w64[rows] / w64[rows].sum(axis=1, keepdims=True), offsets)
            noise = np.stack([rngs[i].standard_normal(particles.shape[1:]) for i in rows])
            copies = (rows, np.take_along_axis(particles[rows], parents[:, :, None], axis=1))
            particles = pf.kernels.jitter_resampled(particles, rows, parents, noise, scale, low, high)
            w[rows] = dtype(1.0 / n)
        yield j + 1, particles, resample, surprise, copies, every


def _contradicted_all(pf: Any, particles: np.ndarray, u: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether a tap's reading (its nearest level) contradicts every particle's predicted reading ``[E]``."""
    levels = np.asarray(pf.model.reading_levels, float)
    read = levels[np.argmin(np.abs(np.asarray(y, float).reshape(-1, 1) - levels[None, :]), axis=1)]
    pred = pf.model.predict(np.asarray(u, float), particles)[..., 0]
    return np.all(pred != read[:, None], axis=1)


def trajectory_rows(beliefs: Any, reading: str, final_k: int, band_inner: float, band_outer: float) -> pd.DataFrame:
    """One row per trajectory of ``beliefs`` (a ``RunBeliefs``) under ``reading``: surprise (running max) and
    escape at k = 1 and ``final_k``, the first tap's band, the hull edges, escape before tap 1's jitter, taps
    contradicting every particle, and the tail's reach past the copies' upper edge at k = 1."""
    from probecommit.runner.seeding import INFERENCE, episode_rngs
    from probecommit.studies.explain.ex14_escape import in_band
    from probecommit.tasks.insertion.model import half_gap

    batch = beliefs.batch.subset(np.flatnonzero(beliefs.batch.status == "ok"))
    pf = beliefs.pfilter
    rngs = episode_rngs(beliefs.config.seed, batch.split, batch.instance_index, batch.repeat, INFERENCE)
    steps = {"linear64": lambda: _linear(pf, np.float64, batch, rngs, final_k),
             "linear32": lambda: _linear(pf, np.float32, batch, rngs, final_k)}
    mode = {"move_next": "next", "first_unjittered": "first"}.get(reading, "stated")
    taps = steps.get(reading, lambda: _log_space(pf, mode, batch, rngs, final_k))()
    z, e = batch.truths[:, 0], batch.n_episodes
    running, every = np.full(e, -np.inf), np.zeros(e, dtype=np.int64)
    out: dict[str, Any] = {}
    for k, particles, resampled, surprise, copies, all_contra in taps:
        running, every = np.maximum(running, surprise), every + all_contra
        lo, hi = particles[:, :, 0].min(axis=1), particles[:, :, 0].max(axis=1)
        if k == 1:
            pre_lo, pre_hi = lo.copy(), hi.copy()
            if copies is not None:
                pre_lo[copies[0]], pre_hi[copies[0]] = copies[1][:, :, 0].min(axis=1), copies[1][:, :, 0].max(axis=1)
            out.update(surprise_k1=running.copy(), escaped_k1=(z < lo) | (z > hi), hull_lo_k1=lo, hull_hi_k1=hi,
                       copies_hi_k1=pre_hi, resampled_k1=resampled, escaped_prejitter_k1=(z < pre_lo) | (z > pre_hi))
        if k == final_k:
            out.update(surprise_final=running.copy(), escaped_final=(z < lo) | (z > hi), hull_hi_final=hi,
                       hull_lo_final=lo)
    u1 = np.asarray(batch.u[:, 0], float).reshape(-1)
    band = in_band(u1, z, half_gap(batch.truths[:, 1]), band_inner, band_outer)
    return pd.DataFrame({"reading": reading, "instance_id": batch.instance_id.astype(str),
                         "repeat": batch.repeat.astype("int64"), "in_band": np.asarray(band, bool),
                         "all_contradicted_taps": every, **out})


#: E106's draws, in its order.
DRAWS = ("b_test", "b_cal", "a", "pool_0", "pool_1")


def _share(flags: np.ndarray) -> float:
    return float(np.mean(flags)) if len(flags) else float("nan")


def _span(out: dict[str, Any], prefix: str, values: list[float]) -> None:
    finite = [v for v in values if np.isfinite(v)]
    out[f"{prefix}.min"] = min(finite) if finite else float("nan")
    out[f"{prefix}.max"] = max(finite) if finite else float("nan")


def reading_keys(rows: pd.DataFrame, draws: Sequence[str], resamples: int, seed: int) -> dict[str, Any]:
    """Per draw: escapes at the final budget, the surprise's cluster-bootstrap AUC at k = 1 and the final budget,
    the band's count and escaped share; over the draws the spans of the point AUCs and of the share."""
    from probecommit.audit.stats import cluster_bootstrap_auc

    out: dict[str, Any] = {}
    auc: dict[str, list[float]] = {"k1": [], "final": []}
    shares = []
    for draw in draws:
        part = rows[rows["draw"] == draw]
        y, band = part["escaped_final"].to_numpy(bool), part["in_band"].to_numpy(bool)
        out[f"{draw}.n"], out[f"{draw}.n_escaped"] = int(len(part)), int(y.sum())
        for k in auc:
            iv = cluster_bootstrap_auc(part[f"surprise_{k}"].to_numpy(float), y, part["instance_id"].to_numpy(),
                                       resamples=resamples, seed=seed)
            out[f"{draw}.auc_{k}"] = [float(iv.estimate), float(iv.lo), float(iv.hi)]
            auc[k].append(float(iv.estimate))
        out[f"{draw}.n_band"], out[f"{draw}.n_band_escaped"] = int(band.sum()), int((band & y).sum())
        out[f"{draw}.band_escaped_share"] = _share(y[band])
        shares.append(out[f"{draw}.band_escaped_share"])
    for k, values in auc.items():
        _span(out, f"auc_{k}", values)
    _span(out, "share", shares)
    out["n_escaped.min"] = min(out[f"{d}.n_escaped"] for d in draws)
    out["n_escaped.max"] = max(out[f"{d}.n_escaped"] for d in draws)
    return out


def trace_keys(rows: pd.DataFrame, draws: Sequence[str]) -> dict[str, Any]:
    """The stated filter's band trajectories, tap 1 to the final budget (no rule reads them): escaped share before
    tap 1's jitter, after it and at the final budget; the share whose hull is the same at k = 1 and the final
    budget; taps contradicting every particle; the jitter tail's mean reach past the copies' upper edge."""
    out: dict[str, Any] = {}
    for draw in draws:
        b = rows[(rows["draw"] == draw) & rows["in_band"]]
        out[f"{draw}.band_share.prejitter_k1"] = _share(b["escaped_prejitter_k1"].to_numpy(bool))
        out[f"{draw}.band_share.k1"] = _share(b["escaped_k1"].to_numpy(bool))
        out[f"{draw}.band_share.final"] = _share(b["escaped_final"].to_numpy(bool))
    b = rows[rows["in_band"]]
    same = (b["hull_lo_k1"] == b["hull_lo_final"]) & (b["hull_hi_k1"] == b["hull_hi_final"])
    out["band.hull_unchanged_share"] = _share(same.to_numpy(bool))
    out["band.resampled_k1_share"] = _share(b["resampled_k1"].to_numpy(bool))
    out["band.n"] = int(len(b))
    out["all_contradicted_taps"] = int(rows["all_contradicted_taps"].sum())
    out["band.all_contradicted_taps"] = int(b["all_contradicted_taps"].sum())
    tail = b[b["resampled_k1"]]
    out["band.tail_reach_mm"] = float((tail["hull_hi_k1"] - tail["copies_hi_k1"]).mean()) if len(tail) else float("nan")
    return out


def keys(rows: pd.DataFrame, resamples: int, seed: int) -> dict[str, Any]:
    """E150's and E151's keys from the stored rows: per reading :func:`reading_keys`, the stated filter's
    :func:`trace_keys`, and the check that the stated replay gives every stored final-budget escape."""
    draws = [d for d in DRAWS if d in set(rows["draw"])]
    out: dict[str, Any] = {"draws": len(draws)}
    for reading in READINGS:
        part = rows[rows["reading"] == reading]
        out.update({f"{reading}.{k}": v for k, v in reading_keys(part, draws, resamples, seed).items()})
    stated = rows[rows["reading"] == "stated"]
    out.update({f"trace.{k}": v for k, v in trace_keys(stated, draws).items()})
    out["w0_reproduces_stored"] = int(bool(len(stated)) and bool(
        (stated["escaped_final"].to_numpy(bool) == stated["stored_escaped_final"].to_numpy(bool)).all()))
    return out
