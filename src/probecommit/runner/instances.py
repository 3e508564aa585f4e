"""Ground-truth instance draws: uniform or Latin-hypercube over a box."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.config import StudyConfig
from probecommit.runner.seeding import instance_rng


def latin_hypercube(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    """``n`` Latin-hypercube points in ``[0, 1)^d``: one per stratum in every coordinate."""
    strata = np.stack([rng.permutation(n) for _ in range(d)], axis=1)
    return (strata + rng.random((n, d))) / n


def draw_instances(config: StudyConfig, model: Any) -> pd.DataFrame:
    """The instance table of a study: id, split, index, ``true_<latent>`` and ``ctx_<name>`` columns.

    Truths are ``count`` draws (uniform or Latin hypercube) from the truth box (the
    model's prior box unless set), or the config's fixed ``truths``; with ``contexts``
    every truth is crossed with every context (truth-major order).
    """
    cfg = config.instances
    latent_names, context_names = tuple(model.latent_names), tuple(model.context_names)
    d = len(latent_names)
    if cfg.truths is not None:
        truths = np.array(cfg.truths, dtype=float).reshape(-1, d)
    else:
        low = np.array(cfg.truth_low if cfg.truth_low is not None else config.model.prior_low, dtype=float)
        high = np.array(cfg.truth_high if cfg.truth_high is not None else config.model.prior_high, dtype=float)
        if np.any(high <= low):
            raise ValueError("instances truth box must have truth_high > truth_low")
        rng = instance_rng(cfg.seed, cfg.split)
        unit = latin_hypercube(rng, cfg.count, d) if cfg.sampling == "lhs" else rng.random((cfg.count, d))
        truths = low + (high - low) * unit
    contexts = np.array(cfg.contexts, dtype=float).reshape(-1, len(context_names)) if cfg.contexts else np.zeros((1, 0))
    truths = np.repeat(truths, len(contexts), axis=0)
    contexts = np.tile(contexts, (len(truths) // len(contexts), 1))
    n = len(truths)
    table = pd.DataFrame(
        {
            "instance_id": [f"{cfg.split}-{i:04d}" for i in range(n)],
            "split": cfg.split,
            "instance_index": np.arange(n, dtype=np.int64),
        }
    )
    for j, name in enumerate(latent_names):
        table[f"true_{name}"] = truths[:, j]
    for j, name in enumerate(context_names):
        table[f"ctx_{name}"] = contexts[:, j]
    return table
