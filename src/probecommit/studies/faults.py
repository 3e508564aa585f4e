"""Controlled mismatch classes (paper Table "Controlled mismatch tests", Fig. "signatures").

Five faults are injected one at a time on top of the corrected model, each with
its known fix and with tempering ``T``:

========== ============================================ ==================================
fault      injection                                    known fix
========== ============================================ ==================================
noise      simulator tap noise x4 (model sigma kept)    model sigma x4
boundary   the deployed tap boundary hg - r             the corrected boundary
prior      truths from +-12 mm under a +-10 mm prior    prior widened to +-12 mm
particles  128 particles, no jitter                     1024 with jitter
frame      +1 mm on the committed aim, simulator side   offset removed
========== ============================================ ==================================

Every arm of a fault reuses one set of stored probes, so arms are paired.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import pandas as pd

from probecommit.runner.replay import CHUNK_INSTANCES, LoadedRun, replay_episodes

FAULTS = ("none", "noise", "boundary", "prior", "particles", "frame")
ROLLOUTS = ("base", "noise", "prior")  # runs the harness needs: the rest are replays of "base"


@dataclass(frozen=True)
class Arm:
    fault: str
    arm: str  # "fault", "fix" or "tempered"
    rollout: str  # which stored run's probes
    overrides: dict[str, dict[str, Any]]


def fault_arms(noise_factor: float, prior_half_width: float, particles: int, frame_offset: float,
               temperature: float, sigma: float) -> list[Arm]:
    """Every (fault, arm) of the harness as a replay of one of the ``ROLLOUTS``."""
    temper = {"likelihood": "tempered", "temperature": temperature}
    deployed = {"boundary": "deployed"}
    few = {"particles": particles, "jitter": False}
    frame = {"aim_offset": frame_offset}
    wide = {"prior_low": (-prior_half_width, 0.7), "prior_high": (prior_half_width, 1.3)}
    return [
        Arm("none", "fault", "base", {}),
        Arm("noise", "fault", "noise", {}),
        Arm("noise", "fix", "noise", {"model": {"sigma": sigma * noise_factor}}),
        Arm("noise", "tempered", "noise", {"belief": temper}),
        Arm("boundary", "fault", "base", {"model": deployed}),
        Arm("boundary", "fix", "base", {}),
        Arm("boundary", "tempered", "base", {"model": deployed, "belief": temper}),
        Arm("prior", "fault", "prior", {}),
        Arm("prior", "fix", "prior", {"model": wide}),
        Arm("prior", "tempered", "prior", {"belief": temper}),
        Arm("particles", "fault", "base", {"belief": few}),
        Arm("particles", "fix", "base", {}),
        Arm("particles", "tempered", "base", {"belief": {**few, **temper}}),
        Arm("frame", "fault", "base", {"simulator": frame}),
        Arm("frame", "fix", "base", {}),
        Arm("frame", "tempered", "base", {"simulator": frame, "belief": temper}),
    ]


def run_fault_harness(rollouts: dict[str, LoadedRun], arms: list[Arm], progress=None,
                      chunk_instances: int | None = CHUNK_INSTANCES) -> pd.DataFrame:
    """Episodes of every arm, tagged with ``fault`` and ``arm`` columns.

    Arms that replay the same rollout under the same overrides (the fixes that are the
    unfaulted model) share one replay: a replay is a deterministic function of the two.
    ``chunk_instances``: instances whose beliefs a replay holds at once.
    """
    frames = []
    replayed: dict[tuple[str, str], pd.DataFrame] = {}
    for n, arm in enumerate(arms):
        key = (arm.rollout, json.dumps(arm.overrides, sort_keys=True, default=str))
        if key not in replayed:
            replayed[key], _ = replay_episodes(rollouts[arm.rollout], arm.overrides, chunk_instances=chunk_instances)
        frames.append(replayed[key].assign(fault=arm.fault, arm=arm.arm))
        if progress:
            progress(n + 1, len(arms))
    return pd.concat(frames, ignore_index=True)


def signature_table(episodes: pd.DataFrame, resamples: int = 2000, seed: int = 7) -> pd.DataFrame:
    """Per (fault, budget) of the fault arms: escape, coverage, optimism and failure.

    The data of the signatures figure; faults in ``FAULTS`` order, budgets ascending;
    each metric with a cluster-bootstrap interval over instances (``<metric>_lo/_hi``),
    the figure's bands.
    """
    from probecommit.audit.stats import cluster_bootstrap_mean

    probe = episodes[(episodes.arm == "fault") & (episodes.method == "probe_robust") & (episodes.status == "ok")]
    probe = probe.assign(optimism=probe.realized - probe.predicted)
    columns = {"escape": "escaped", "coverage": "covered", "optimism": "optimism", "failure": "realized"}
    rows = []
    for (fault, k), group in probe.groupby(["fault", "k"], sort=False):
        row = {"fault": fault, "k": k}
        for name, col in columns.items():
            ci = cluster_bootstrap_mean(group[col].to_numpy(float), group["instance_id"].to_numpy(), resamples=resamples,
                                        seed=seed)
            row.update({name: ci.estimate, f"{name}_lo": ci.lo, f"{name}_hi": ci.hi})
        rows.append(row)
    table = pd.DataFrame(rows)
    table = table[["fault", "k", *columns, *[f"{n}_{e}" for n in columns for e in ("lo", "hi")]]]
    rank = table["fault"].map({f: i for i, f in enumerate(FAULTS)})
    return table.assign(_r=rank).sort_values(["_r", "k"], kind="stable").drop(columns="_r").reset_index(drop=True)
