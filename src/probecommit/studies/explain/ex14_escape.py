"""k = 1 escape as a band event, and the readings of the paper's filter sentence (E112..E114).

Why: the paper's original model escapes more than ours (Split B random: k = 1 0.055 against 0.021,
k = 8 0.169 against 0.102; T36's 50 final escapes against 28), and Table III's optimism and T36's k = 1
AUC both depend on which episodes escape. At k = 1 escape is nearly a closed-form event: a first tap in
the band ``hg(c) - r <= |u - x_hole| < hg(c) + delta_sim`` reads pocket in the simulator and top in the
model, and the truth then survives in the hull only if the resampled, jittered, clipped copies reach it.
So ``escape_1 = P(band) x P(escape | band) + P(escape, off band)``; ``P(band)`` is exact from the prior
box and the nine tap positions, ``P(escape | band)`` is the filter's. This module computes the exact
``P(band)``, and replays stored taps under the declared readings of the filter sentence
(docs/decisions.md, "ex14"), recording per trajectory and budget the hull, escape and running-max
surprise (no engine run; the filter's own per-episode seeds).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable, Sequence

import numpy as np
import pandas as pd

#: The readings, in the order the selection rule scans them (R0 first: ours).
READINGS = ("stated", "prejitter", "duplicates", "every_step")


def band_length(u: float, half_gap: np.ndarray, inner: float, outer: float, low: float, high: float) -> np.ndarray:
    """Length of ``{x in [low, high]: half_gap + inner <= |u - x| < half_gap + outer}`` per half-gap value
    (both sides of the tap), each side cut by the prior box."""
    total = np.zeros_like(np.asarray(half_gap, dtype=float))
    for sign in (1.0, -1.0):
        a = u + sign * (half_gap + inner)
        b = u + sign * (half_gap + outer)
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        total += np.clip(np.minimum(hi, high) - np.maximum(lo, low), 0.0, None)
    return total


def p_band(taps: Sequence[float], x_box: tuple[float, float], c_box: tuple[float, float],
           half_gap: Callable[[np.ndarray], np.ndarray], inner: float, outer: float, grid: int = 200_001) -> float:
    """P(first tap in the band) for ``x ~ U(x_box)``, ``c ~ U(c_box)``, the tap uniform over ``taps``.

    The band length is piecewise linear in ``c``; the mean over ``c`` is taken on a midpoint grid of
    ``grid`` points (error below 1e-8 for the insertion prior)."""
    c = c_box[0] + (np.arange(grid) + 0.5) / grid * (c_box[1] - c_box[0])
    hg = half_gap(c)
    width = x_box[1] - x_box[0]
    return float(np.mean([band_length(u, hg, inner, outer, *x_box).mean() / width for u in taps]))


def in_band(u: np.ndarray, x: np.ndarray, hg: np.ndarray, inner: float, outer: float) -> np.ndarray:
    """Whether each tap ``u`` lies in its truth's band (``hg + inner <= |u - x| < hg + outer``)."""
    d = np.abs(np.asarray(u, float) - np.asarray(x, float))
    return (d >= hg + inner) & (d < hg + outer)


class _Recorder:
    """A ``jitter_resampled`` kernel that keeps the step's resampled copies before their jitter
    (``prejitter``) and, with ``duplicates_only``, leaves each parent's first copy unjittered."""

    def __init__(self, kernel: Callable[..., np.ndarray], duplicates_only: bool) -> None:
        self.kernel, self.duplicates_only, self.copies = kernel, duplicates_only, None

    def __call__(self, particles, rows, parents, noise, scale, low, high):
        self.copies = (np.asarray(rows), np.take_along_axis(particles[rows], parents[:, :, None], axis=1))
        if self.duplicates_only:
            first = np.ones(parents.shape, dtype=bool)
            first[:, 1:] = parents[:, 1:] != parents[:, :-1]
            noise = np.where(first[:, :, None], 0.0, noise)
        return self.kernel(particles, rows, parents, noise, scale, low, high)


def reading_filter(pfilter: Any, reading: str) -> tuple[Any, _Recorder]:
    """The filter of one reading (its kernel records each step's pre-jitter copies)."""
    if reading not in READINGS:
        raise ValueError(f"unknown reading {reading!r}; one of {READINGS}")
    recorder = _Recorder(pfilter.kernels.jitter_resampled, reading == "duplicates")
    pf = replace(pfilter, kernels=replace(pfilter.kernels, jitter_resampled=recorder))
    if reading == "every_step":
        pf = replace(pf, resample_fraction=1.0)  # resample when ESS < N: after every informative tap
    return pf, recorder


def replay_rows(beliefs: Any, reading: str, budgets: Sequence[int], coordinate: int = 0) -> pd.DataFrame:
    """One row per trajectory and budget of ``beliefs`` (a ``RunBeliefs``) under ``reading``: the hull of
    the decision coordinate as the reading measures it, escape, the running-max surprise and whether the
    step resampled."""
    from probecommit.runner.seeding import INFERENCE, episode_rngs

    batch = beliefs.batch.subset(np.flatnonzero(beliefs.batch.status == "ok"))
    pf, recorder = reading_filter(beliefs.pfilter, reading)
    rngs = episode_rngs(beliefs.config.seed, batch.split, batch.instance_index, batch.repeat, INFERENCE)
    state = pf.initial(rngs)
    z = batch.truths[:, coordinate]
    running = np.full(batch.n_episodes, -np.inf)
    parts, keep = [], set(int(k) for k in budgets)
    for j in range(1, max(keep) + 1):
        recorder.copies = None
        state = pf.update(state, batch.u[:, j - 1], batch.y[:, j - 1], rngs)
        running = np.maximum(running, -state.log_evidence)
        if j not in keep:
            continue
        measured = state.particles[:, :, coordinate]
        if reading == "prejitter" and recorder.copies is not None:
            rows, copies = recorder.copies
            measured = measured.copy()
            measured[rows] = copies[:, :, coordinate]
        lo, hi = measured.min(axis=1), measured.max(axis=1)
        parts.append(pd.DataFrame({
            "reading": reading, "instance_id": batch.instance_id.astype(str), "repeat": batch.repeat.astype("int64"),
            "k": j, "z_true": z, "hull_lo": lo, "hull_hi": hi, "escaped": (z < lo) | (z > hi),
            "max_surprise": running.copy(), "resampled": np.asarray(state.resampled, bool)}))
    return pd.concat(parts, ignore_index=True)


def committed_original(run: Any, reading: str, budgets: Sequence[int], chunk_instances: int | None = 48) -> pd.DataFrame:
    """The original arm (the run's nu, the model's margin) re-committed on ``run`` at ``budgets`` under a
    reading that changes the belief (``duplicates``, ``every_step``); its ``escaped`` is the hull of all
    particles of that belief. Stored taps and readings, no engine run beyond the run's cached aims."""
    from probecommit.runner.calibration import load_for_commit
    from probecommit.runner.replay import RunBeliefs, load_run

    loaded = load_run(run)
    beliefs = RunBeliefs.of(loaded, chunk_instances=chunk_instances, budgets=budgets)
    loaded.beliefs = replace(beliefs, pfilter=reading_filter(beliefs.pfilter, reading)[0])
    target = load_for_commit(loaded)
    [table] = target.commit((target.nu, None), final=True)
    return table
