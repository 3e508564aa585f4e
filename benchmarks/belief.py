"""Belief + executor per episode-step: the batched core against a plain per-episode loop, in one run.

The plain loop is the textbook filter the paper describes, written here independently
of the package (NumPy, one episode at a time): Gaussian reweighting in log space,
ESS < N/2 -> systematic resampling + jitter + clip, the top-weight 0.8-mass retained
set by a stable sort, and the scenario failure fraction of every aim by broadcasting.
Both arms see the same data and draw the same random numbers in the same order, and
both run once as a warm-up (numba compilation, allocator). Then the arms take turns for
``--rounds`` rounds (a shared virtual machine's speed drifts by 10-30 % within a minute,
so one timing per arm is not a ratio): each arm's median is printed, and the ratio of
the medians with the smallest and largest ratio of a single round. The process keeps freed
arrays in its heap as the ``probecommit`` command does (``process.memory.reuse_freed_arrays``;
the plain loop's arrays are too small to be affected); ``--default-heap`` leaves glibc's defaults.

    python benchmarks/belief.py [--episodes 384] [--particles 1024] [--taps 8] [--rounds 5] [--default-heap]
                                [--without-mh]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from probecommit.accel import production
from probecommit.core.belief import ParticleFilter
from probecommit.core.executors import ProbeRobust
from probecommit.process.memory import reuse_freed_arrays
from probecommit.tasks.insertion.model import InsertionModel, capture_half_width, half_gap


def make_data(episodes: int, taps: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    model = InsertionModel.deployed()
    truths = np.column_stack([rng.uniform(-10, 10, episodes), rng.uniform(0.7, 1.3, episodes)])
    u = model.probe_grid[rng.integers(0, 9, (episodes, taps))]  # [E, K, 1]
    y = np.stack([model.predict(u[:, j], truths[:, None, :])[:, 0, :] for j in range(taps)], axis=1)
    return model, u, y + 0.5 * rng.standard_normal(y.shape)


def run_core(pf, model, u, y, seeds):
    rngs = [np.random.default_rng(s) for s in seeds]
    state = pf.initial(rngs)
    executor = ProbeRobust(model, kernels=production().sets)  # the production path, as the runner injects it
    actions = []
    for j in range(u.shape[1]):
        state = pf.update(state, u[:, j], y[:, j], rngs)
        actions.append(executor.act(state.particles, state.weights, 0.8).index)
    return state, np.stack(actions, axis=1)


def run_plain(model, u, y, seeds, n, sigma=0.5):
    """The textbook filter and scenario executor, one episode at a time (no package code)."""
    low, high = np.array([-10.0, 0.7]), np.array([10.0, 1.3])
    scale = np.array([0.6, 0.006])
    aims = model.action_grid[:, 0]
    out_particles, out_actions = [], []
    for e, s in enumerate(seeds):
        rng = np.random.default_rng(s)
        particles = low + (high - low) * rng.random((n, 2))
        logw = np.full(n, -np.log(n))
        chosen = []
        for j in range(u.shape[1]):
            pocket = np.abs(u[e, j, 0] - particles[:, 0]) < half_gap(particles[:, 1]) - 1.2
            pred = np.where(pocket, -15.0, 0.0)
            logw = logw - 0.5 * ((y[e, j, 0] - pred) / sigma) ** 2
            logw -= logw.max() + np.log(np.sum(np.exp(logw - logw.max())))
            w = np.exp(logw)
            if 1.0 / np.sum(w * w) < 0.5 * n:
                cum = np.cumsum(w)
                cum[-1] = 1.0
                parents = np.minimum(np.searchsorted(cum, (rng.random() + np.arange(n)) / n, side="right"), n - 1)
                particles = np.clip(particles[parents] + scale * rng.standard_normal((n, 2)), low, high)
                logw = np.full(n, -np.log(n))
                w = np.exp(logw)
            order = np.argsort(-w, kind="stable")
            m = int(np.argmax(np.cumsum(w[order]) >= 0.8 - 1e-12)) + 1
            kept = particles[order[:m]]
            window = capture_half_width(kept[:, 1])
            success = (kept[None, :, 0] - window[None, :] < aims[:, None]) & (aims[:, None] < kept[None, :, 0] + window[None, :])
            fails = m - success.sum(axis=1)
            best = np.flatnonzero(fails == fails.min())
            ref = np.sum(w[order[:m]] * kept[:, 0]) / np.sum(w[order[:m]])
            chosen.append(best[np.argmin(np.abs(aims[best] - ref))])
        out_particles.append(particles)
        out_actions.append(chosen)
    return np.stack(out_particles), np.array(out_actions)


def add_heap_option(parser: argparse.ArgumentParser) -> None:
    """``--default-heap``: measure with glibc's default heap thresholds instead of the command's."""
    parser.add_argument("--default-heap", action="store_true", help="glibc's default heap thresholds, not the command's")


def heap_setting(args: argparse.Namespace) -> str:
    """Set the command's heap thresholds (``process.memory.reuse_freed_arrays``) unless ``--default-heap``; say which."""
    return "glibc's default heap" if args.default_heap or not reuse_freed_arrays() else "the command's heap thresholds"


def timed(fn, *args):
    t0 = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - t0, out


def interleaved(arms: dict, rounds: int) -> tuple[dict, dict]:
    """Each arm once as a warm-up, then ``rounds`` rounds in turn: ``({arm: [seconds]}, {arm: output})``."""
    outputs = {name: fn() for name, fn in arms.items()}  # warm-up: numba compilation, allocator
    times: dict = {name: [] for name in arms}
    for _ in range(rounds):
        for name, fn in arms.items():
            times[name].append(timed(fn)[0])
    return times, outputs


def ratio_text(times: dict, slow: str, fast: str) -> str:
    """``median(slow) / median(fast)`` and the range of the per-round ratios."""
    per_round = [s / f for s, f in zip(times[slow], times[fast])]
    return (f"{float(np.median(times[slow]) / np.median(times[fast])):.2f}x "
            f"(rounds {min(per_round):.2f}-{max(per_round):.2f}, {len(per_round)} rounds)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=384)
    ap.add_argument("--particles", type=int, default=1024)
    ap.add_argument("--taps", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=5)
    add_heap_option(ap)
    ap.add_argument("--without-mh", action="store_true",
                    help="time only the two arms of the comparison (the resample-move arm's large allocations slow "
                         "the arm after it by a few us here)")
    args = ap.parse_args()
    heap = heap_setting(args)
    model, u, y = make_data(args.episodes, args.taps)
    seeds = list(range(args.episodes))
    steps = args.episodes * args.taps
    kernels = production().filter
    pf = ParticleFilter.gaussian(model, model.sigma, n_particles=args.particles, kernels=kernels)
    pf_mh = ParticleFilter.gaussian(model, model.sigma, n_particles=args.particles, move="mh", kernels=kernels)
    arms = {
        "core": lambda: run_core(pf, model, u, y, seeds),
        "mh": lambda: run_core(pf_mh, model, u, y, seeds),
        "plain": lambda: run_plain(model, u, y, seeds, args.particles),
    }
    if args.without_mh:
        del arms["mh"]
    times, out = interleaved(arms, args.rounds)
    (state, actions), (particles, plain_actions) = out["core"], out["plain"]
    same_particles = np.array_equal(state.particles, particles)
    same_actions = np.array_equal(actions, plain_actions)
    med = {name: float(np.median(t)) for name, t in times.items()}
    print(f"E={args.episodes} N={args.particles} taps={args.taps}: update + retained set + executor per episode-step "
          f"(median of {args.rounds} interleaved rounds, {heap})")
    print(f"  batched core (jitter, the paper):  {med['core'] / steps * 1e6:7.1f} us per episode-step  ({med['core']:.2f} s)")
    if "mh" in med:
        print(f"  batched core (move = mh):          {med['mh'] / steps * 1e6:7.1f} us per episode-step  ({med['mh']:.2f} s)")
    print(f"  plain per-episode NumPy loop:      {med['plain'] / steps * 1e6:7.1f} us per episode-step  ({med['plain']:.2f} s)")
    print(f"  ratio plain / core: {ratio_text(times, 'plain', 'core')}   identical particles: {same_particles}   "
          f"identical aims: {same_actions}")


if __name__ == "__main__":
    main()
