"""Grasp's blind-held truths against the squeeze's duration in MuJoCo (E178, E179; ex26, issue #36; rules declared in
``docs/decisions.md``, "ex26").

Why: our probed grip loses, on 25 to 49 % of seeds, the truths the blind grip holds, where the paper's numbers need
them held on every seed. A squeeze's slip is (1/2) g T^2 (1 - u / F_hold)^+: the squeeze's duration T (ours 50 ms,
unreported) sets both how much eight squeezes tell about the hold force against sigma = 2 mm and, against that,
how much MuJoCo's fixed soft-contact offset (about +0.6 mm a squeeze) biases the commit. E49 scaled the slip on the
analytic scene only; this step reruns the frozen MuJoCo grasp study with T = 50 sqrt(c) ms in both the model and
the engine (:func:`squeeze_scale`), at the frozen force ceiling (E178) and at E133's two ceilings with about six
feasible truths (E179, :func:`probecommit.studies.explain.ex18_grasp.force_ceiling`), and counts the per-truth
signs as Table II reads them, with the blind-held truths' probed failures beside them.
"""

from __future__ import annotations

import gc
import math
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np
import pandas as pd

#: The stored rows the keys are counted from (``breadth.truth_rows`` with each episode's grip ``action`` and the
#: truth's hold force of the lift ``z_true``, per condition).
STORED = "ex26_grasp_rows.parquet"
#: Result group.
GROUP = "ex26_grasp"
#: The declared conditions: (key prefix, the gripper's force ceiling in N per pad, c, the squeeze's slip scale over
#: the frozen one, T = 50 sqrt(c) ms). ``c1`` is the frozen row (a check). A quick run has them all.
CONDITIONS = (("c1", 5.0, 1.0), ("c2", 5.0, 2.0), ("c4", 5.0, 4.0), ("cap20_c4", 2.0, 4.0), ("cap25_c4", 2.5, 4.0))
#: The paper's seeds on the two truths its blind grip holds (2 x 80): E73's chance that both tie.
PAPER_HELD_SEEDS = 160


@contextmanager
def squeeze_scale(c: float) -> Iterator[None]:
    """The squeeze's duration multiplied by ``sqrt(c)`` (its slip scale by ``c``) in the model and in the MuJoCo
    squeeze inside the block, the frozen duration restored after it (whatever happens inside). Engine answers are
    not shared with runs outside the block (``tasks.base``'s answer store is set aside for it): a squeeze of another
    duration is another query under the same key."""
    from probecommit.tasks import base
    from probecommit.tasks.grasp import model, sim_mujoco

    saved = model.SQUEEZE_S, sim_mujoco.SQUEEZE_S, model.GraspModel.observation_range, base._ANSWER_STORE
    low, high = saved[2]
    model.SQUEEZE_S = sim_mujoco.SQUEEZE_S = saved[0] * math.sqrt(float(c))
    model.GraspModel.observation_range = (low, high * float(c))
    base._ANSWER_STORE = None
    try:
        yield
    finally:
        model.SQUEEZE_S, sim_mujoco.SQUEEZE_S, model.GraspModel.observation_range, base._ANSWER_STORE = saved


def condition_rows(config: Any, path: Path) -> pd.DataFrame:
    """A run's ``breadth.truth_rows`` with each episode's grip (``action``, N) and the truth's ``z_true`` (F_lift)."""
    from probecommit.studies.breadth import truth_rows

    rows = truth_rows(config, path)
    episodes = pd.read_parquet(path / "episodes.parquet", columns=["action", "z_true"]).reset_index(drop=True)
    return rows.assign(action=episodes["action"].to_numpy(), z_true=episodes["z_true"].to_numpy())


def rows_of(runs: Path, quick: bool, conditions: Sequence[tuple[str, float, float]] = CONDITIONS) -> pd.DataFrame:
    """Per declared condition, one MuJoCo grasp run of the frozen config (``condition`` column), serial: the
    ceiling and the duration live in this process's modules, so no worker process may build its own."""
    from probecommit.runner.study import run_study
    from probecommit.studies.explain.ex18_grasp import ceiling_config, force_ceiling

    frames = []
    for name, limit, c in conditions:
        config = ceiling_config(limit, quick, name=f"grasp_squeeze_{name}")
        path = runs / config.name
        with force_ceiling(float(limit)), squeeze_scale(float(c)):
            run_study(config, path, workers=1, threads=1)
            frames.append(condition_rows(config, path).assign(condition=name, ceiling=float(limit), c=float(c)))
        gc.collect()  # the run's simulator and its compiled MuJoCo scenes go before the next run builds its own
    return pd.concat(frames, ignore_index=True)


def held_summary(rows: pd.DataFrame) -> dict[str, Any]:
    """The feasible truths the blind grip holds (Blind-Bayes success 1) and Probe-Robust(8)'s seeds on them: how
    many fail, how many of those crush (grip at least 1.5 F_lift), the probed grip's median over F_lift, E73's chance
    that two such truths tie over the paper's 2 x 80 seeds, and the lowest probed success over the feasible truths."""
    from probecommit.studies.breadth import FAMILY_K, arm
    from probecommit.tasks.grasp.model import CRUSH_RATIO

    ep = rows[rows["feasible"].astype(bool)]
    blind = 1.0 - arm(ep, "blind_bayes", 0).groupby("truth")["realized"].mean()
    probed = arm(ep, "probe_robust", FAMILY_K["grasp"])
    held = probed[probed["truth"].isin(blind.index[blind == 1.0])]
    failed = held[held["realized"] == 1.0]
    rate = float(failed.shape[0] / held.shape[0]) if len(held) else float("nan")
    return {"held_truths": int((blind == 1.0).sum()), "held_seeds": int(len(held)), "held_failures": int(len(failed)),
            "held_crush": int((failed["action"] >= CRUSH_RATIO * failed["z_true"]).sum()),
            "held_grip_ratio": float(np.median(held["action"] / held["z_true"])) if len(held) else float("nan"),
            "held_tie_chance": float((1.0 - rate) ** PAPER_HELD_SEEDS),
            "lowest_probed": float((1.0 - probed.groupby("truth")["realized"].mean()).min())}


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per condition (``<name>.``): its ceiling and c, the feasible truths' signs (``grasp_x.sign_counts``, with the
    worst difference) and :func:`held_summary`. One function for the step and verify."""
    from probecommit.studies.explain.grasp_x import sign_counts

    out: dict[str, Any] = {}
    for name, r in rows.groupby("condition", sort=False):
        body = r.drop(columns=["condition", "ceiling", "c"])
        got = {"ceiling": float(r["ceiling"].iloc[0]), "c": float(r["c"].iloc[0]), **sign_counts(body, worst=True),
               **held_summary(body)}
        out.update({f"{name}.{k}": v for k, v in got.items()})
    return out


def run(explain: Any) -> None:
    """The explain step, set aside to a process of its own (``Explain.aside``: the duration and ceiling patch the
    grasp modules in that process only): the reruns, their rows stored and the ``ex26_grasp`` keys counted from
    them."""
    explain.progress("explain: grasp's blind-held truths against the squeeze's duration (E178, E179)", 0, 1)
    rows = rows_of(explain.runs, bool(explain.quick))
    explain.stored[STORED] = rows
    explain.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "held_summary", "rows_of", "squeeze_scale", "CONDITIONS")
