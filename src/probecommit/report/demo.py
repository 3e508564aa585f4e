"""The demo's report: per-budget table and the belief figure of one episode."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from probecommit.report.figures import belief_snapshots
from probecommit.store.safefile import write_with
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


def belief_figure(run_dir: str | Path, out: str | Path | None = None, series: str | Path | None = None) -> Path:
    """The belief snapshot (Fig. 1b style) of a run's illustrative episode; returns the PNG path.

    ``series``: where to write the figure's data series too (``report.figures.belief_series``), for a
    publication to store and ``verify`` to draw the figure again from."""
    from probecommit.report.figures import belief_series, draw_belief_snapshots

    loaded = load_run(run_dir)
    trace, model, _ = trace_for_run(loaded)
    row = illustrative_episode(trace, loaded.episodes)
    budgets = tuple(k for k in FIGURE_BUDGETS if k in trace.states) or tuple(trace.budgets[:3])
    data = belief_series(trace, model, loaded.episodes, row, budgets)
    if series is not None:
        write_with(Path(series), lambda buf: data.to_parquet(buf, compression="zstd", index=False))
    return draw_belief_snapshots(data, Path(out or run_dir) / "belief.png")


def _trend(first: float, last: float, signed: bool = False) -> str:
    """``rises from +0.008 to +0.283`` (or ``falls``, or ``stays near``), the numbers as the table prints them."""
    fmt = "{:+.3f}" if signed else "{:.3f}"
    a, b = fmt.format(first), fmt.format(last)
    if a == b:
        return f"stays at {a}"
    return f"{'rises' if last > first else 'falls'} from {a} to {b}"


def explain_budget_table(table) -> list[str]:
    """Three sentences that read the per-budget table (:func:`budget_summary`) to its reader, every
    number taken from it: how optimism and the two failure curves move with the budget, how coverage
    and escape move, and how the probing executor compares with the blind ones."""
    probing = table[table["k"] >= 1]
    if probing.empty:
        return []
    method = "probe_robust" if (probing["method"] == "probe_robust").any() else str(probing["method"].iloc[0])
    rows = probing[probing["method"] == method].sort_values("k")
    lo, hi = rows.iloc[0], rows.iloc[-1]
    name = {"probe_robust": "Probe-Robust"}.get(method, method)
    k = f"k = {int(lo['k'])} to {int(hi['k'])}"
    lines = [
        f"Optimism e_k (realized - predicted) {_trend(lo['optimism'], hi['optimism'], True)} over {k}: "
        f"{name}'s predicted failure {_trend(lo['predicted'], hi['predicted'])}, its realized failure "
        f"{_trend(lo['failure'], hi['failure'])}.",
        f"Coverage (the truth inside the retained set) {_trend(lo['coverage'], hi['coverage'])}, support escape "
        f"(the truth outside every particle) {_trend(lo['escape'], hi['escape'])}"
        + (": more taps make the belief surer without keeping the truth in it."
           if hi["coverage"] < lo["coverage"] and hi["optimism"] > lo["optimism"] else "."),
    ]
    blind = table[table["k"] == 0]
    if not blind.empty:
        labels = {"blind_bayes": "Blind-Bayes", "blind_robust": "Blind-Robust"}
        parts = ", ".join(f"{labels.get(str(r['method']), r['method'])} {r['failure']:.3f}" for _, r in blind.iterrows())
        lines.append(f"With no taps the blind executors fail {parts}; {name} at k = {int(hi['k'])} fails "
                     f"{hi['failure']:.3f}.")
    return lines


def next_command(run_dir: str | Path, boundary: str) -> str | None:
    """The command that replays an insertion run's taps under the other tap model (None otherwise)."""
    other = {"deployed": "corrected", "corrected": "deployed"}.get(boundary)
    return f"probecommit replay {Path(run_dir).as_posix()} --model {other}" if other else None


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
        *[f"- {line}" for line in explain_budget_table(table)],
        "",
        *([f"Next: `{cmd}` replays the same taps under the other tap model.", ""]
          if (cmd := next_command(run_dir, str(getattr(loaded.config.model, "boundary", "")))) else []),
        f"Engine calls: {manifest.get('engine_calls')}; engine time {manifest.get('timing', {}).get('engine_s', float('nan')):.1f} s.",
        "",
        f"![belief after taps {', '.join(map(str, FIGURE_BUDGETS))}]({figure.name})",
        "",
    ]
    report = Path(run_dir) / "report.md"
    write_text(report, "\n".join(lines))
    return report
