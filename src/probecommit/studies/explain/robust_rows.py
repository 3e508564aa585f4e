"""The mixture filter replayed when the model is right and on Test C: the stored rows and their keys.

Why: ``explain:results.robust`` summarizes replays (the frozen base run and Test C's deployed run
re-inferred under the mixture likelihood) a publication cannot hold. The explain step stores each
replay's final-budget rows (``STORED``) and fills the keys by calling :func:`keys` on them; verify
calls it on the stored copy, with Test C's deployed rows from the insertion study's stored episodes
and the harness's optimism from the insertion study's robust filters recomputed from their rows.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import pandas as pd

#: The replays' final-budget Probe-Robust rows: ``part`` ``right_base`` (the base run as run), ``right_mixture``
#: (replayed at ``epsilon``), ``testc_mixture`` (Test C's deployed run replayed at the chosen epsilon).
STORED = "robust_replays.parquet"
COLUMNS = ("part", "epsilon", "instance_id", "repeat", "k", "action", "predicted", "realized", "escaped")


def table(parts: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """The stored rows of each part (``part`` and ``epsilon`` columns assigned)."""
    return pd.concat([part[list(COLUMNS)] for part in parts], ignore_index=True)


def keys(rows: pd.DataFrame, testc_deployed: pd.DataFrame, insertion_robust: Mapping[str, Any],
         boot: Mapping[str, int]) -> dict[str, Any]:
    """``robust.*``: the mixture's failure and changed aims when the model is right at every epsilon, its optimism,
    escape and paired failure change on Test C against the deployed rows, and the harness's optimism per filter
    (the insertion study's robust results)."""
    from probecommit.audit.stats import paired_bootstrap

    part = lambda name: rows[rows["part"] == name].reset_index(drop=True)  # noqa: E731
    base = part("right_base")
    out: dict[str, Any] = {"right_model.failure": float(base["realized"].mean())}
    aims = base.set_index(["instance_id", "repeat"])["action"]
    for eps, replay in part("right_mixture").groupby("epsilon", sort=False):
        out[f"right_model.mixture_eps{eps:g}.failure"] = float(replay["realized"].mean())
        out[f"right_model.mixture_eps{eps:g}.changed_aims"] = float(
            (replay.set_index(["instance_id", "repeat"])["action"] != aims).mean())
    mix, dep = part("testc_mixture"), testc_deployed
    out["testc.deployed.optimism"] = float((dep["realized"] - dep["predicted"]).mean())
    out["testc.mixture.optimism"] = float((mix["realized"] - mix["predicted"]).mean())
    out["testc.mixture.escape"] = float(mix["escaped"].mean())
    d = paired_bootstrap(dep, mix, "realized", resamples=int(boot["resamples"]), seed=int(boot["seed"])).difference
    out["testc.mixture.failure_change"] = [float(d.estimate), float(d.lo), float(d.hi)]
    out["harness.deployed.optimism"] = float(insertion_robust["deployed"]["optimism"][0])
    for family in ("mixture", "rejuvenation"):
        if family in insertion_robust:
            out[f"harness.{family}.optimism"] = float(insertion_robust[family]["optimism"][0])
    return out
