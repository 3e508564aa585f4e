"""The robot study (paper Sec. V-D): Table VII and Fig. 5b-d on the simulated rig.

We have no arm, so this runs the frozen rig protocol (``configs/paper/rig.yaml``) as a
robot session against the simulated rig (MuJoCo, touch-switch descent) through the same
:class:`~probecommit.robot.session.Session` a physical rig uses, then audits the log
(Table VII: by number of taps, episodes, in window, entered, predicted, realized,
optimism; coverage; aim error against taps with a cluster bootstrap over positions,
Fig. 5b) and replays its recorded taps under the two injected faults: the tap boundary
pulled inward by 0..14 mm (Fig. 5c) and the prior narrowed (Fig. 5d). A real rig's log
goes through the same functions (``probecommit audit LOG``, ``probecommit replay LOG``).
The paper's Table VII (the physical arm) is quoted beside ours for comparison only, in columns
labelled as the physical arm's; every artifact of this study says it comes from the simulated rig
(:data:`RIG_LABEL`, ``results.json``'s ``"rig": "simulated"``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import pandas as pd

from probecommit.audit.stats import DEFAULT_RESAMPLES
from probecommit.robot.replay import fault_sweep, replay_session
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import SessionEpisodes, robot_table, session_episodes
from probecommit.runner.config import StudyConfig, config_data, load_config, parse_config

#: What produced this study's artifacts: printed in every table, figure and results.json it writes.
RIG_LABEL = "simulated rig (no physical arm)"
#: The paper's Table VII columns (physical arm), by key in ``paper_values``.
PAPER_COLUMNS = ("episodes", "in_window", "entered", "predicted", "realized", "optimism")
#: Fault sizes (mm): boundary pull-in 0..14 mm; prior half-widths from the deployed 38.6 mm down.
BOUNDARY_SWEEP = [float(v) for v in range(15)]
PRIOR_SWEEP = [38.6, 30.0, 24.0, 18.0, 12.0, 8.0]
#: The simulation's 2.1 mm boundary error at rig scale (Fig. 5c's dotted line).
SIM_ERROR_AT_RIG_SCALE_MM = 2.1 * 3.86


def rig_config(quick: bool = False) -> StudyConfig:
    """The frozen rig protocol; quick: 4 positions, 1 episode per budget, 512 particles, analytic rig."""
    from probecommit import paper_config

    config = load_config(paper_config("rig"))
    if not quick:
        return config
    data = config_data(config)
    data["instances"]["count"] = 4
    data["repeats"] = 1
    data["belief"]["particles"] = 512
    data["simulator"]["engine"] = "analytic"
    return parse_config(data)


def table_markdown(table: pd.DataFrame) -> str:
    """Table VII on the simulated rig, the physical arm's values in a column that says so."""
    from probecommit.studies.paper_values import PRINTED as PAPER

    lines = ["| taps | episodes (sim. rig) | in window (sim. rig) | entered (sim. rig) | predicted (sim. rig) | "
             "realized (sim. rig) | optimism [95% CI] (sim. rig) | coverage (sim. rig) | aim error mm [95% CI] "
             "(sim. rig) | paper, physical arm: episodes / in window / entered / predicted / realized / optimism |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in table.itertuples(index=False):
        cells = [PAPER.get(f"tab:hardware.{int(r.taps)}.{c}") for c in PAPER_COLUMNS]
        paper = " / ".join(cells) if all(cells) else "--"
        lines.append(f"| {r.taps} | {r.episodes} | {r.in_window} | {int(r.entered)} | {r.predicted:.3f} | "
                     f"{r.realized:.3f} | {r.optimism:+.3f} [{r.optimism_lo:+.3f}, {r.optimism_hi:+.3f}] | "
                     f"{r.covered}/{r.episodes} | {r.aim_error:.1f} [{r.aim_error_lo:.1f}, {r.aim_error_hi:.1f}] | {paper} |")
    return "\n".join(lines) + "\n"


def sweep_markdown(sweep: pd.DataFrame, label: str) -> str:
    lines = [f"| {label} | coverage | escape | optimism | failure | d optimism [95% CI] | d coverage [95% CI] |",
             "|---|---|---|---|---|---|---|"]
    for r in sweep.itertuples(index=False):
        star = lambda flag: " (resolved)" if flag else ""  # noqa: E731
        lines.append(f"| {r.size:g} | {r.coverage:.3f} | {r.escape:.3f} | {r.optimism:+.3f} | {r.failure:.3f} | "
                     f"{r.delta_optimism:+.3f} [{r.delta_optimism_lo:+.3f}, {r.delta_optimism_hi:+.3f}]{star(r.optimism_resolved)} | "
                     f"{r.delta_coverage:+.3f} [{r.delta_coverage_lo:+.3f}, {r.delta_coverage_hi:+.3f}]{star(r.coverage_resolved)} |")
    return "\n".join(lines) + "\n"


@dataclass
class RobotStudy:
    """What the robot study measured (written out by ``report.paper``)."""

    config: StudyConfig
    episodes: SessionEpisodes
    table: pd.DataFrame
    reproduced: float
    boundary: pd.DataFrame
    prior: pd.DataFrame
    #: The sweeps' replay rows (``robot.replay.fault_sweep``'s record): what verify computes the sweeps from.
    sweep_episodes: pd.DataFrame | None = None
    resamples: int = DEFAULT_RESAMPLES

    def _prior_by_position(self) -> dict[str, Any]:
        """E222's split of the narrowed prior's signature, at the share of positions beyond that the paper's escape
        implies (its block positions are not reported); empty without stored sweep rows."""
        if self.sweep_episodes is None:
            return {}
        from probecommit.studies.paper_values import value

        return {f"{PRIOR_SIGNATURE_MM:g}": prior_by_position(self.sweep_episodes, self.episodes.rows,
                                                             share=value("T29-replay-prior.escape"))}

    def payload(self) -> dict[str, Any]:
        rows = self.episodes.rows
        resolved = self.boundary[self.boundary["optimism_resolved"] & (self.boundary["size"] > 0)]
        return {
            "results": {
                "rig": "simulated", "label": RIG_LABEL,
                "config": config_data(self.config), "engine": self.config.simulator.engine,
                "episodes": int(len(rows)), "positions": int(rows["instance_id"].nunique()),
                "n_covered": int(rows["covered"].sum()), "n_escaped": int(rows["escaped"].sum()),
                "replay_reproduced_fraction": self.reproduced,
                "table": json.loads(self.table.to_json(orient="records")),
                "boundary_fault": json.loads(self.boundary.to_json(orient="records")),
                "prior_fault": json.loads(self.prior.to_json(orient="records")),
                "boundary_first_resolved_mm": float(resolved["size"].min()) if len(resolved) else None,
                "boundary_holds_to_mm": boundary_holds_to(self.boundary),
                "optimism_pooled": float((rows["realized"] - rows["predicted"]).mean()),
                "boundary_by_mm": sweep_by_size(self.boundary), "prior_by_mm": sweep_by_size(self.prior),
                "prior_by_position": self._prior_by_position(),
                "unscored": self.episodes.unscored,
                "sweep_resamples": int(self.resamples),
            },
        }


def sweep_by_size(sweep: pd.DataFrame) -> dict[str, Any]:
    """A fault sweep's rows by size (``"12"``, ``"38.6"``), so a claim can name one."""
    return {f"{float(r['size']):g}": r for r in json.loads(sweep.to_json(orient="records"))}


#: The narrowed prior at which the paper reports its signature (Sec. V-D, T29), half-width in mm at rig scale.
PRIOR_SIGNATURE_MM = 12.0


def prior_by_position(sweep_episodes: pd.DataFrame, session: pd.DataFrame, size: float = PRIOR_SIGNATURE_MM,
                      share: float | None = None) -> dict[str, Any]:
    """The narrowed-prior replay at ``size`` split by where each block position lies: beyond the narrowed prior
    (``|z| > size``) or inside it.

    Why: escape and coverage under a narrowed prior are, if the belief cannot reach past its prior, the share of
    positions beyond it, a property of where the blocks were put, which the paper does not report (E222). The
    split measures that mechanism position by position (``positions_escape_is_beyond``: the positions every episode
    of which escapes if beyond and none if inside) and gives each stratum's optimism, so the optimism at another share of positions
    beyond (``share``, e.g. the one the paper's escape implies) is their mixture.
    """
    part = sweep_episodes[(sweep_episodes["fault"] == "prior") & (sweep_episodes["size"] == size)]
    z = session.groupby("instance_id")["z_true"].first()
    rows = part.assign(beyond=part["instance_id"].map(z).abs() > size,
                       optimism=part["realized"].astype(float) - part["predicted"].astype(float))
    per_position = rows.groupby("instance_id").agg(beyond=("beyond", "first"), escaped=("escaped", "mean"))
    out: dict[str, Any] = {
        "positions": int(len(per_position)), "share_beyond": float(per_position["beyond"].mean()),
        "positions_escape_is_beyond": int((per_position["escaped"] == per_position["beyond"].astype(float)).sum()),
        "optimism_beyond": float(rows.loc[rows["beyond"], "optimism"].mean()),
        "optimism_inside": float(rows.loc[~rows["beyond"], "optimism"].mean())}
    if share is not None:
        out["share"] = float(share)
        out["optimism_at_share"] = share * out["optimism_beyond"] + (1 - share) * out["optimism_inside"]
    return out


def boundary_holds_to(sweep: pd.DataFrame) -> float:
    """The largest size up to which no coverage change is resolved (the sweep's last size if none is)."""
    rows = sweep.sort_values("size")
    resolved = rows[rows["coverage_resolved"].astype(bool) & (rows["size"] > 0)]
    before = rows[rows["size"] < resolved["size"].min()] if len(resolved) else rows
    return float(before["size"].max())


def run_robot_study(runs: Path, *, quick: bool = False, progress: Callable[[str, int, int], None] | None = None,
                    resamples: int = DEFAULT_RESAMPLES) -> RobotStudy:
    """Run the simulated rig session into ``runs``, audit it and replay it under both faults."""
    config = rig_config(quick)
    log = simulate_session(runs / ("rig-quick" if quick else "rig"), config,
                           progress=(lambda d, t: progress("rig session", d, t)) if progress else None)
    episodes = session_episodes(log)
    table = robot_table(episodes.rows, resamples=resamples)
    _, reproduced = replay_session(log)
    boundary_sizes = BOUNDARY_SWEEP[::7] if quick else BOUNDARY_SWEEP
    prior_sizes = PRIOR_SWEEP[::2] if quick else PRIOR_SWEEP

    def tick(name: str, sizes: list[float]) -> Callable[[float], None] | None:
        if progress is None:
            return None
        return lambda size: progress(name, sizes.index(size) + 1, len(sizes))

    kept: list[pd.DataFrame] = []
    boundary, _ = fault_sweep(log, "boundary", boundary_sizes, resamples=resamples, progress=tick("boundary fault", boundary_sizes),
                              record=kept)
    prior, _ = fault_sweep(log, "prior", prior_sizes, resamples=resamples, progress=tick("prior fault", prior_sizes),
                           record=kept)
    return RobotStudy(config, episodes, table, reproduced, boundary, prior, pd.concat(kept, ignore_index=True), resamples)
