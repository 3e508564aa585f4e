"""Ground-truth instance draws: uniform or Latin-hypercube over a box."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from probecommit.runner.config import StudyConfig
from probecommit.runner.seeding import instance_rng

if TYPE_CHECKING:
    import pandas as pd


def latin_hypercube(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    """``n`` Latin-hypercube points in ``[0, 1)^d``: one per stratum in every coordinate."""
    strata = np.stack([rng.permutation(n) for _ in range(d)], axis=1)
    return (strata + rng.random((n, d))) / n


class InstanceTable:
    """An instance table as its columns (NumPy arrays, in table order): what a run's own path reads of its
    instances (a column, a range of rows, the length) without a DataFrame, whose pandas import was about
    0.2 s of a run's CPU (docs/decisions.md, "run: ..."). :meth:`to_frame` is :func:`draw_instances`' table."""

    def __init__(self, columns: dict[str, np.ndarray]):
        self.columns = columns

    @classmethod
    def of(cls, table: "InstanceTable | pd.DataFrame") -> "InstanceTable":
        """``table`` as an :class:`InstanceTable` (a DataFrame's columns as its ``to_numpy`` gives them)."""
        if isinstance(table, InstanceTable):
            return table
        return cls({str(name): table[name].to_numpy() for name in table.columns})

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def rows(self, index: slice | np.ndarray) -> "InstanceTable":
        """The rows ``index`` (a slice or positions), as ``DataFrame.iloc`` takes them."""
        return InstanceTable({name: values[index] for name, values in self.columns.items()})

    def to_frame(self) -> "pd.DataFrame":
        import pandas as pd

        return pd.DataFrame(self.columns)


def draw_instances(config: StudyConfig, model: Any) -> pd.DataFrame:
    """:func:`instance_table` as a DataFrame."""
    return instance_table(config, model).to_frame()


def instance_table(config: StudyConfig, model: Any) -> InstanceTable:
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
    columns = {
        "instance_id": np.array([f"{cfg.split}-{i:04d}" for i in range(n)], dtype=object),
        "split": np.full(n, cfg.split, dtype=object),
        "instance_index": np.arange(n, dtype=np.int64),
    }
    for j, name in enumerate(latent_names):
        columns[f"true_{name}"] = np.ascontiguousarray(truths[:, j])
    for j, name in enumerate(context_names):
        columns[f"ctx_{name}"] = np.ascontiguousarray(contexts[:, j])
    return InstanceTable(columns)
