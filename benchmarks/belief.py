"""Belief-update throughput: the batched core against a per-episode loop, in one run.

Also, with ``--run RUN_DIR``, the share of a finished study's wall time spent in the
engine (from its manifest) against everything else.

    python benchmarks/belief.py [--episodes 384] [--particles 1024] [--run runs/demo]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from probecommit.core.belief import ParticleFilter
from probecommit.runner.inference import _choose
from probecommit.core.retained import retained_mask, weighted_mean
from probecommit.tasks.insertion.model import InsertionModel


def make_data(episodes: int, taps: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    model = InsertionModel.deployed()
    truths = np.column_stack([rng.uniform(-10, 10, episodes), rng.uniform(0.7, 1.3, episodes)])
    u = model.probe_grid[rng.integers(0, 9, (episodes, taps))]
    y = np.stack([model.predict(u[:, j], truths[:, None, :])[:, 0, :] for j in range(taps)], axis=1)
    return model, u, y + 0.5 * rng.standard_normal(y.shape)


def run_batched(pf, model, u, y, seeds):
    rngs = [np.random.default_rng(s) for s in seeds]
    state = pf.initial(rngs)
    for j in range(u.shape[1]):
        state = pf.update(state, u[:, j], y[:, j], rngs)
        mask = retained_mask(state.weights, 0.8)
        _choose(model, state.particles, mask, weighted_mean(model.decision(state.particles), state.weights, mask))
    return state


def run_loop(pf, model, u, y, seeds):
    states = []
    for e, s in enumerate(seeds):
        rngs = [np.random.default_rng(s)]
        state = pf.initial(rngs)
        for j in range(u.shape[1]):
            state = pf.update(state, u[e : e + 1, j], y[e : e + 1, j], rngs)
            mask = retained_mask(state.weights, 0.8)
            _choose(model, state.particles, mask, weighted_mean(model.decision(state.particles), state.weights, mask))
        states.append(state)
    return states


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=384)
    ap.add_argument("--particles", type=int, default=1024)
    ap.add_argument("--taps", type=int, default=8)
    ap.add_argument("--run", type=Path, default=None, help="a finished run directory for the engine share")
    args = ap.parse_args()
    model, u, y = make_data(args.episodes, args.taps)
    pf = ParticleFilter.gaussian(model, model.sigma, n_particles=args.particles)
    seeds = list(range(args.episodes))
    t0 = time.perf_counter()
    batched = run_batched(pf, model, u, y, seeds)
    t_batched = time.perf_counter() - t0
    t0 = time.perf_counter()
    looped = run_loop(pf, model, u, y, seeds)
    t_loop = time.perf_counter() - t0
    same = all(np.array_equal(batched.particles[e], s.particles[0]) for e, s in enumerate(looped))
    updates = args.episodes * args.taps
    print(f"E={args.episodes} N={args.particles} taps={args.taps} (update + retained set + executor per tap)")
    print(f"  batched core:      {updates / t_batched:10.0f} episode-updates/s  ({t_batched:.2f} s)")
    print(f"  per-episode loop:  {updates / t_loop:10.0f} episode-updates/s  ({t_loop:.2f} s)")
    print(f"  ratio batched/loop: {t_loop / t_batched:.1f}x   identical results: {same}")
    if args.run:
        manifest = json.loads((args.run / "manifest.json").read_text())
        timing = manifest["timing"]
        wall = timing.get("units_wall_s", timing["this_invocation_wall_s"])
        print(f"run {args.run}: engine {timing['engine_s']:.1f} s of {wall:.1f} s unit wall time "
              f"({100 * timing['engine_s'] / wall:.0f}% engine, {100 * (1 - timing['engine_s'] / wall):.0f}% everything else); "
              f"engine calls {manifest['engine_calls']}")


if __name__ == "__main__":
    main()
