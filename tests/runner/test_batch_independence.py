"""An episode's result never depends on the batch it ran in (batches of 1, 7 and all)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from probecommit.runner.build import build_executors, build_filter, build_model, build_simulator
from probecommit.runner.inference import build_trace, commit, rollout
from probecommit.runner.instances import draw_instances
from tests.conftest import small_config


def test_rows_are_bit_identical_in_batches_of_1_7_and_all():
    config = small_config(instances={"count": 24, "seed": 4}, probes={"budget": 8}, belief={"particles": 512},
                          repeats=2)
    model = build_model(config)
    simulator = build_simulator(config)
    instances = draw_instances(config, model)
    batch = rollout(instances, config.repeats, "random", 8, model, simulator, config.seed)
    pfilter = build_filter(model, config.belief)

    def episodes(rows: np.ndarray) -> pd.DataFrame:
        trace = build_trace(pfilter, batch.subset(rows), config.seed, range(1, 9))
        return commit(trace, model, simulator, build_executors(("blind_robust", "probe_robust"), model), thresholds=0.8)

    everything = episodes(np.arange(batch.n_episodes))
    for size in (1, 7):
        parts = [episodes(np.arange(start, min(start + size, batch.n_episodes)))
                 for start in range(0, batch.n_episodes, size)]
        pd.testing.assert_frame_equal(pd.concat(parts, ignore_index=True), everything, check_exact=True)
    # Resampling happened, so the resampler's batch handling was exercised.
    assert (everything["n_retained"] < 512).any()
