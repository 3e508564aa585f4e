"""Ground-truth instance draws: uniform or Latin-hypercube over a box."""

from __future__ import annotations

import numpy as np
import pandas as pd

from probecommit.runner.config import StudyConfig
from probecommit.runner.seeding import instance_rng


def latin_hypercube(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    """``n`` Latin-hypercube points in ``[0, 1)^d``: one per stratum in every coordinate."""
    strata = np.stack([rng.permutation(n) for _ in range(d)], axis=1)
    return (strata + rng.random((n, d))) / n


def draw_instances(config: StudyConfig, latent_names: tuple[str, ...]) -> pd.DataFrame:
    """The instance table of a study: id, split, index and ``true_<latent>`` columns."""
    cfg = config.instances
    low = np.array(cfg.truth_low if cfg.truth_low is not None else config.model.prior_low, dtype=float)
    high = np.array(cfg.truth_high if cfg.truth_high is not None else config.model.prior_high, dtype=float)
    if np.any(high <= low):
        raise ValueError("instances truth box must have truth_high > truth_low")
    rng = instance_rng(cfg.seed, cfg.split)
    d = len(latent_names)
    unit = latin_hypercube(rng, cfg.count, d) if cfg.sampling == "lhs" else rng.random((cfg.count, d))
    truths = low + (high - low) * unit
    table = pd.DataFrame(
        {
            "instance_id": [f"{cfg.split}-{i:04d}" for i in range(cfg.count)],
            "split": cfg.split,
            "instance_index": np.arange(cfg.count, dtype=np.int64),
        }
    )
    for j, name in enumerate(latent_names):
        table[f"true_{name}"] = truths[:, j]
    return table
