"""Is each instance set a typical draw of its generator, and do the audit metrics depend on the draw?

The insertion truth box is ``x_hole ~ U[-10, 10]`` mm; a hole beyond +-7 mm (30 % of the box)
leaves room for fewer informative taps on one side. The generator test redraws every split's
instances under many seeds (the same stream :func:`runner.instances.draw_instances` uses,
checked against it for the frozen seed) and places the frozen draw among them. The
stratified audit splits a run's episodes by hole position and standardizes each metric to
the generator's expected mix, so two draws can be compared on equal terms.
"""

from __future__ import annotations

from typing import Any, Iterable

import numpy as np
import pandas as pd

from probecommit.runner.seeding import instance_rng
from probecommit.studies.explain.stats import percentile_of, standardized_mean

#: Metric -> episode column (optimism is realized - predicted).
METRICS = {"escape": "escaped", "episode_coverage": "covered", "optimism": "optimism", "failure": "realized"}


def share_beyond(x: np.ndarray, edge: float) -> float:
    """Fraction of holes with ``|x| > edge``."""
    return float(np.mean(np.abs(np.asarray(x, dtype=float)) > edge))


def redraw_shares(split: str, count: int, low: float, high: float, edge: float, seeds: Iterable[int]) -> np.ndarray:
    """Share of holes beyond ``edge`` in the uniform draws of ``split`` under each seed."""
    out = []
    for seed in seeds:
        unit = instance_rng(int(seed), split).random((count, 2))
        out.append(share_beyond(low + (high - low) * unit[:, 0], edge))
    return np.asarray(out)


def generator_test(instances: pd.DataFrame, split: str, seed: int, low: float, high: float, edge: float,
                   seeds: int) -> dict[str, Any]:
    """The frozen draw of one split against ``seeds`` redraws of the same generator.

    Raises:
        AssertionError: the redraw for the frozen seed differs from the stored instances
            (the test would then be about another generator).
    """
    x = instances["true_x_hole"].to_numpy(float)
    count = len(x)
    mine = instance_rng(int(seed), split).random((count, 2))
    np.testing.assert_allclose(low + (high - low) * mine[:, 0], x, rtol=0, atol=1e-12)
    shares = redraw_shares(split, count, low, high, edge, range(seeds))
    realized = share_beyond(x, edge)
    expected = (max(high - edge, 0.0) + max(-edge - low, 0.0)) / (high - low)
    return {"realized_share": realized, "redraw_mean": float(shares.mean()), "redraw_sd": float(shares.std(ddof=1)),
            "expected_share": expected, "binomial_sd": float(np.sqrt(expected * (1 - expected) / count)),
            "percentile": percentile_of(realized, shares), "seeds": int(seeds), "count": count}


#: The frozen draws the generator test reads: per run its split, seed, redraw count and holes in instance order.
STORED = "generator_instances.parquet"
#: The instance box of the uniform generator (mm).
BOX = (-10.0, 10.0)


def generator_table(runs: dict[str, tuple[pd.DataFrame, str, int]], seeds: int) -> pd.DataFrame:
    """The stored rows: per run name ``(instances, split, seed)``, one row per instance in the run's order."""
    parts = [pd.DataFrame({"run": name, "split": split, "seed": int(seed), "seeds": int(seeds),
                           "true_x_hole": instances["true_x_hole"].to_numpy(float)})
             for name, (instances, split, seed) in runs.items()]
    return pd.concat(parts, ignore_index=True)


def generator_keys(table: pd.DataFrame, edge: float) -> dict[str, Any]:
    """``instance_generator.<run>.*``: each run's frozen draw against redraws of its generator (``generator_test``)."""
    out: dict[str, Any] = {}
    for name, rows in table.groupby("run", sort=False):
        first = rows.iloc[0]
        test = generator_test(rows, str(first["split"]), int(first["seed"]), *BOX, edge, int(first["seeds"]))
        out.update({f"{name}.{k}": v for k, v in test.items()})
    return out


def analytic_equals_mujoco(draws: pd.DataFrame, mujoco: pd.DataFrame) -> dict[str, int]:
    """``draws.analytic_equals_mujoco_escape_k8``: the frozen run redrawn on the analytic scene (the fresh draws'
    first row) escapes as the stored MuJoCo run does (``mujoco``: its final-budget Probe-Robust rows)."""
    return {"draws.analytic_equals_mujoco_escape_k8": int(abs(draws.iloc[0]["escape_k8"] - mujoco["escaped"].mean()) < 1e-12)}


def stratified_metrics(episodes: pd.DataFrame, k: int, edge: float, expected_share: float) -> dict[str, Any]:
    """Each metric at budget ``k`` for holes inside and beyond ``edge``, and standardized to ``expected_share``.

    Args:
        episodes: Episode table (probe executor rows are used).
        k: Budget.
        edge: Stratum boundary on ``|x_hole|`` (mm).
        expected_share: The generator's share of holes beyond ``edge``.
    """
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok") & (episodes["k"] == k)]
    rows = rows.assign(optimism=rows["realized"].astype(float) - rows["predicted"].astype(float))
    stratum = np.where(np.abs(rows["z_true"].to_numpy(float)) > edge, "beyond", "inside")
    out: dict[str, Any] = {"share_beyond": float(np.mean(stratum == "beyond")), "n": int(len(rows))}
    weights = {"inside": 1.0 - expected_share, "beyond": expected_share}
    for name, column in METRICS.items():
        values = rows[column].to_numpy(float)
        out[f"{name}.all"] = float(values.mean())
        for s in ("inside", "beyond"):
            out[f"{name}.{s}"] = float(values[stratum == s].mean()) if np.any(stratum == s) else float("nan")
        out[f"{name}.standardized"] = standardized_mean(values, stratum, weights)
    return out
