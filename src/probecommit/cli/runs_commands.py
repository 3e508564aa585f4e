"""``probecommit runs`` (a table of earlier runs, ``runs compare A B``) and the overrides and sweeps of
``probecommit run CONFIG key=value ... --sweep key=a,b``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer
from rich import box
from rich.table import Table

from probecommit.cli.common import console, safe, user_errors
from probecommit.cli.output import number
from probecommit.errors import UsageError

#: Written into a run directory made with overrides: the source file and the override list
#: (``config.yaml`` beside it is the effective config).
OVERRIDES_FILE = "overrides.yaml"


def _num(value, signed: bool = False) -> str:
    return number(value, signed, missing="-")


def _text(value) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else safe(value)


def _print(table: Table) -> None:
    from probecommit.cli.output import print_table

    print_table(table)


# ----------------------------------------------------------------------------- run overrides and sweeps


def record_overrides(run_dir: Path, source: Path, overrides: list[str], sweep: list[str] | None = None) -> None:
    """Write ``overrides.yaml`` into the run directory (atomically): the config file and the overrides
    applied to it, in order; ``config.yaml`` is the result."""
    import yaml

    from probecommit.store.rundir import atomic_write_bytes

    data = {"config_file": str(source), "overrides": list(overrides)}
    if sweep:
        data["sweep"] = list(sweep)
    text = "# config.yaml is config_file with these overrides applied, in order\n" + yaml.safe_dump(data, sort_keys=False)
    atomic_write_bytes(run_dir / OVERRIDES_FILE, text.encode())


def run_config_with_overrides(config: Path, overrides: list[str], sweeps: list[str], out: Optional[Path],
                              runner) -> None:
    """``probecommit run CONFIG [key=value ...] [--sweep key=a,b ...]``: one run, or one per sweep point
    (each its own run directory under ``runs/<name>-sweep/``, run one after the other on the chosen
    backend by ``runner(cfg, out) -> StudyResult``), then a summary table."""
    from probecommit.runner.overrides import (format_override, load_with_overrides, parse_override, parse_sweep,
                                              point_label, sweep_grid)

    fixed = [parse_override(item) for item in overrides]
    if not sweeps:
        cfg = load_with_overrides(config, fixed)
        result = runner(cfg, out or Path("runs") / cfg.name, title=f"{cfg.name}: per-budget summary")
        if fixed:
            record_overrides(result.run_dir, config, [format_override(o) for o in fixed])
        return
    grid = sweep_grid([parse_sweep(item) for item in sweeps])
    configs = [load_with_overrides(config, fixed + point) for point in grid]  # every point valid before any runs
    root = out or Path("runs") / f"{configs[0].name}-sweep"
    rows = []
    for point, cfg in zip(grid, configs):
        run_dir = root / point_label(point)
        label = " ".join(format_override(o) for o in point)
        result = runner(cfg, run_dir, title=f"{cfg.name} {label}: per-budget summary")
        record_overrides(result.run_dir, config, [format_override(o) for o in fixed + point],
                         [format_override(o) for o in point])
        from probecommit.report.runs import headline

        rows.append({"point": label, "run": str(result.run_dir), **headline(result.episodes)})
    print_sweep_summary(rows, root)


def print_sweep_summary(rows: list[dict], root: Path) -> None:
    """One row per sweep point: the probe method's failure, optimism and coverage at its last budget;
    also written to ``<root>/sweep.csv``."""
    import pandas as pd

    from probecommit.cli.output import write_csv

    table = Table(title=f"sweep: {len(rows)} runs ({rows[0]['method']} at the last budget)", title_style="bold",
                  box=box.SIMPLE_HEAD)
    for col in ("point", "k", "failure", "optimism", "coverage", "run"):
        table.add_column(col, justify="left" if col in ("point", "run") else "right")
    for r in rows:
        table.add_row(safe(r["point"]), str(r["k"]), _num(r["failure"]), _num(r["optimism"], True),
                      _num(r["coverage"]), safe(r["run"]))
    _print(table)
    write_csv(pd.DataFrame(rows), root / "sweep.csv")
    console.print(f"sweep summary: {safe(root / 'sweep.csv')}")


def print_demo_reading(episodes, run_dir: Path, boundary: str) -> None:
    """Below the demo's table: three lines that read it, and the command to run next."""
    from probecommit.report.demo import explain_budget_table, next_command
    from probecommit.report.tables import budget_summary

    for line in explain_budget_table(budget_summary(episodes)):
        console.print(safe(line), highlight=False)
    command = next_command(run_dir, boundary)
    if command:
        console.print(f"next: {safe(command)}  (the same taps under the {'corrected' if boundary == 'deployed' else 'deployed'} "
                      "tap model)", highlight=False)


# ----------------------------------------------------------------------------- runs


def runs_command(
    args: Optional[list[str]] = typer.Argument(
        None, metavar="DIR | compare A B",
        help="A folder to list the runs under (default: runs), or 'compare' and two run directories."),
    resamples: int = typer.Option(2000, min=100, help="compare: paired cluster-bootstrap resamples."),
    seed: int = typer.Option(0, help="compare: bootstrap seed."),
    budgets: Optional[str] = typer.Option(None, help="compare: comma-separated budgets (default: all)."),
) -> None:
    """List earlier runs (name, task, engine, episodes, headline numbers, code, status), or compare two.

    'probecommit runs [DIR]' lists every run directory under DIR (default runs/).
    'probecommit runs compare A B' shows the config fields that differ and, per
    method and budget, both runs' failure, optimism and coverage with B - A and
    a paired cluster-bootstrap interval when both hold the same instances.
    """
    args = list(args or [])
    if args and args[0] == "compare":
        if len(args) != 3:
            raise UsageError("runs compare takes two run directories: probecommit runs compare A B")
        from probecommit.cli.audit_commands import _parse_budgets

        compare(Path(args[1]), Path(args[2]), resamples, seed, _parse_budgets(budgets))
        return
    if len(args) > 1:
        raise UsageError(f"runs takes one folder (or 'compare A B'), got {len(args)} arguments")
    list_table(Path(args[0]) if args else Path("runs"))


def list_table(root: Path) -> None:
    from probecommit.report.runs import list_runs

    frame = list_runs(root)
    if frame.empty:
        console.print(f"no run directories under {safe(root)}")
        return
    table = Table(title=f"runs under {safe(root)}", title_style="bold", box=box.SIMPLE_HEAD)
    for col in ("run", "task", "engine", "episodes", "k", "failure", "optimism", "coverage", "code", "status"):
        table.add_column(col, justify="right" if col in ("episodes", "k", "failure", "optimism", "coverage") else "left")
    for _, r in frame.iterrows():
        path = Path(r["run"])
        name = str(path.relative_to(root)) if path != root and path.is_relative_to(root) else str(path)
        k = r.get("k")
        table.add_row(safe(name), _text(r.get("task")), _text(r.get("engine")), _text(r.get("episodes")),
                      "-" if k is None or k != k else str(int(k)), _num(r.get("failure")),
                      _num(r.get("optimism"), True), _num(r.get("coverage")), _text(r.get("code")), _text(r.get("status")))
    _print(table)
    console.print("headline: the probe method at each run's last budget k; 'runs compare A B' for a paired comparison")


def compare(a: Path, b: Path, resamples: int, seed: int, budgets: Optional[list[int]]) -> None:
    from probecommit.report.runs import compare_runs

    c = compare_runs(a, b, resamples=resamples, seed=seed, budgets=budgets)
    console.print(f"A: {safe(a)}\nB: {safe(b)}")
    if c.config.empty:
        console.print("config: identical")
    else:
        table = Table(title="config fields that differ", title_style="bold", box=box.SIMPLE_HEAD)
        for col in ("field", "A", "B"):
            table.add_column(col)
        for _, r in c.config.iterrows():
            table.add_row(safe(r["field"]), safe(r["a"]), safe(r["b"]))
        _print(table)
    how = ("paired: same instances, 95% paired cluster-bootstrap interval" if c.paired
           else "unpaired: the runs hold different instances, no interval")
    table = Table(title=f"metrics, B - A ({how})", title_style="bold", box=box.SIMPLE_HEAD)
    for col in ("method", "k", "metric", "A", "B", "B - A", "interval"):
        table.add_column(col, justify="left" if col in ("method", "metric") else "right")
    for _, r in c.metrics.iterrows():
        signed = r["metric"] == "optimism"
        interval = f"[{_num(r['lo'], True)}, {_num(r['hi'], True)}]" if r["lo"] == r["lo"] else "-"
        table.add_row(safe(r["method"]), str(r["k"]), safe(r["metric"]), _num(r["a"], signed), _num(r["b"], signed),
                      _num(r["diff"], True), interval)
    _print(table)


def register(app: typer.Typer) -> None:
    """Register ``runs`` on the main app."""
    app.command("runs")(user_errors(runs_command))
