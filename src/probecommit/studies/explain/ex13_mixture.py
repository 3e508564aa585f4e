"""The mixture's cost when the model is right under every reading of q0's units (E107, T44).

Why: the paper's contamination mixture ``(1 - eps) p + eps q0`` has ``p`` the tap's Gaussian and
``q0`` "uniform over the 19 mm observable height range"; at eps = 0.01 ours costs nothing when the
model is right, the paper's 0.102 -> 0.167. A particle's weight depends only on the floor's ratio
to the Gaussian's constant, ``rho = eps q0 / ((1 - eps) c_p)``, so how ``q0`` and ``p`` are
normalized, and in which unit, sets the mixture's strength at the same eps. Each declared reading
(docs/decisions.md, "ex13", written before the run) maps exactly to the epsilon that gives its rho in
our implementation (``q0 = 1 / width`` per mm, ``c_p = 1 / (sigma sqrt(2 pi))`` per mm); the fault
harness's base run (right model, stored taps) is replayed under each, with and without the mixture,
over a few filter seeds.
"""

from __future__ import annotations

import math
from typing import Any

import pandas as pd

from probecommit.runner.replay import LoadedRun
from probecommit.studies.explain.replay_final import replay_at
from probecommit.studies.explain.mixture_x import reseeded

#: The stored rows (one per filter seed and reading) the keys are summarized from.
STORED = "ex13_mixture_units.parquet"
#: The declared readings: name -> (q0's value, the Gaussian's constant c_p), each a function of the mixture
#: range's width (mm) and sigma (mm). A metre is 1000 mm: a density per metre is 1000 x the one per mm.
READINGS = {
    "ours": (lambda w, s: 1 / w, lambda w, s: 1 / (s * math.sqrt(2 * math.pi))),
    "kernel": (lambda w, s: 1 / w, lambda w, s: 1.0),
    "mass_kernel": (lambda w, s: 1.0, lambda w, s: 1.0),
    "mass_density": (lambda w, s: 1.0, lambda w, s: 1 / (s * math.sqrt(2 * math.pi))),
    "q0_per_metre": (lambda w, s: 1000 / w, lambda w, s: 1 / (s * math.sqrt(2 * math.pi))),
    "q0_per_metre_kernel": (lambda w, s: 1000 / w, lambda w, s: 1.0),
    "p_per_metre": (lambda w, s: 1 / w, lambda w, s: 1000 / (s * math.sqrt(2 * math.pi))),
}


def effective_epsilon(reading: str, epsilon: float, width_mm: float, sigma_mm: float) -> float:
    """The epsilon that gives ``reading``'s floor-to-Gaussian ratio in our implementation, where ``q0`` is a
    density per mm and the Gaussian one too: same ratio, so the same weights after normalization."""
    q0, c_p = (f(width_mm, sigma_mm) for f in READINGS[reading])
    ours_q0, ours_c = (f(width_mm, sigma_mm) for f in READINGS["ours"])
    odds = epsilon / (1 - epsilon) * (q0 / c_p) / (ours_q0 / ours_c)
    return odds / (1 + odds)


def _final(episodes: pd.DataFrame, k: int) -> pd.DataFrame:
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok") & (episodes["k"] == k)]
    return rows.sort_values(["instance_id", "repeat"]).reset_index(drop=True)


def run(base: LoadedRun, epsilon: float, low: float, high: float, seeds: list[int], k: int
        ) -> tuple[dict[str, Any], pd.DataFrame]:
    """Keys of ``explain:results.ex13_mixture`` (``summary``) and the rows: ``base`` replayed under each filter
    seed without the mixture and with it under every reading's effective epsilon."""
    sigma = float(base.config.model.sigma)
    rows = []
    for seed in seeds:
        loaded = reseeded(base, seed)
        right = _final(replay_at(loaded, None, k), k)  # only budget k is read: only it is committed (issue 42)
        for reading in READINGS:
            eff = effective_epsilon(reading, epsilon, high - low, sigma)
            belief = {"likelihood": "mixture", "epsilon": eff, "mixture_low": low, "mixture_high": high}
            mixed = _final(replay_at(loaded, {"belief": belief}, k), k)
            rows.append({"seed": int(seed), "reading": reading, "epsilon": float(epsilon), "effective_epsilon": eff,
                         "right": float(right["realized"].mean()), "mixed": float(mixed["realized"].mean()),
                         "changed": float((right["action"].to_numpy() != mixed["action"].to_numpy()).mean())})
    table = pd.DataFrame(rows, columns=["seed", "reading", "epsilon", "effective_epsilon", "right", "mixed", "changed"])
    return summary(table), table


def summary(table: pd.DataFrame) -> dict[str, Any]:
    """Per reading: its effective epsilon, failure with the mixture and the paired cost over seeds (mean, min,
    max), the share of changed aims; the right model's failure over seeds (the step and ``verify`` call this)."""
    out: dict[str, Any] = {"seeds": int(table["seed"].nunique()), "epsilon": float(table["epsilon"].iloc[0])}
    right = table.drop_duplicates("seed")["right"].to_numpy(float)
    out["right.failure.mean"] = float(right.mean())
    for reading in READINGS:
        part = table[table["reading"] == reading]
        if part.empty:
            continue
        cost = part["mixed"].to_numpy(float) - part["right"].to_numpy(float)
        out[f"{reading}.effective_epsilon"] = float(part["effective_epsilon"].iloc[0])
        out[f"{reading}.failure.mean"] = float(part["mixed"].mean())
        out[f"{reading}.paired_cost.mean"] = float(cost.mean())
        out[f"{reading}.paired_cost.min"] = float(cost.min())
        out[f"{reading}.paired_cost.max"] = float(cost.max())
        out[f"{reading}.changed_aims.mean"] = float(part["changed"].mean())
    return out


def covering(values: dict[str, Any], cost: float) -> list[str]:
    """The readings whose paired costs over seeds span ``cost`` (what E107's ``supports`` asks for)."""
    return [r for r in READINGS if f"{r}.paired_cost.min" in values
            and values[f"{r}.paired_cost.min"] <= cost <= values[f"{r}.paired_cost.max"]]

