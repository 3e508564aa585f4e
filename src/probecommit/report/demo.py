"""The demo's report: per-budget table and the belief figure of one episode."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from probecommit.report.figures import belief_snapshots
from probecommit.report.tables import budget_summary, to_markdown
from probecommit.runner.replay import load_run, trace_for_run
from probecommit.store.safefile import write_text

FIGURE_BUDGETS = (1, 3, 5)


def illustrative_episode(trace, episodes) -> int:
    """First episode (run order) whose first five taps read the pocket at least once and
    whose k=5 commit entered; the first episode if none does. Never chosen by outcome alone."""
    batch = trace.batch
    for row in range(batch.n_episodes):
        pocket = np.any(batch.y[row, :5, 0] < -7.5)
        hit = episodes[
            (episodes.instance_id == batch.instance_id[row]) & (episodes.repeat == batch.repeat[row])
            & (episodes.k == 5) & (episodes.method == "probe_robust")
        ]
        if pocket and len(hit) and float(hit["realized"].iloc[0]) == 0.0:
            return row
    return 0


def belief_figure(run_dir: str | Path, out: str | Path | None = None) -> Path:
    """The belief snapshot (Fig. 1b style) of a run's illustrative episode; returns the PNG path."""
    loaded = load_run(run_dir)
    trace, model, _ = trace_for_run(loaded)
    row = illustrative_episode(trace, loaded.episodes)
    budgets = tuple(k for k in FIGURE_BUDGETS if k in trace.states) or tuple(trace.budgets[:3])
    return belief_snapshots(trace, model, loaded.episodes, row, budgets, Path(out or run_dir) / "belief.png")


def write_demo_report(run_dir: str | Path) -> Path:
    """Write ``report.md`` and ``belief.png`` into the run directory; returns the report path."""
    loaded = load_run(run_dir)
    trace, model, _ = trace_for_run(loaded)
    row = illustrative_episode(trace, loaded.episodes)
    figure = belief_snapshots(trace, model, loaded.episodes, row, FIGURE_BUDGETS, Path(run_dir) / "belief.png")
    table = budget_summary(loaded.episodes)
    manifest = loaded.manifest
    lines = [
        f"# probecommit demo: {loaded.config.name}",
        "",
        f"Engine: {loaded.config.simulator.engine}; model: {loaded.config.model.boundary} tap boundary; "
        f"{loaded.config.instances.count} instances x {loaded.config.repeats} repeats, "
        f"probes: {loaded.config.probes.schedule if isinstance(loaded.config.probes.schedule, str) else 'fixed schedule'}.",
        "",
        "Failure is realized; predicted is the executor's scenario failure fraction; "
        "optimism = failure - predicted; coverage: truth inside the retained interval; "
        "escape: truth outside every particle.",
        "",
        to_markdown(table),
        "",
        f"Engine calls: {manifest.get('engine_calls')}; engine time {manifest.get('timing', {}).get('engine_s', float('nan')):.1f} s.",
        "",
        f"![belief after taps {', '.join(map(str, FIGURE_BUDGETS))}]({figure.name})",
        "",
    ]
    report = Path(run_dir) / "report.md"
    write_text(report, "\n".join(lines))
    return report
