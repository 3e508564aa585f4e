"""``probecommit audit``, ``calibrate`` and ``gates``: typer commands over :mod:`probecommit.audit`.

Registered on the main app by :func:`register`. Each prints rich tables and writes
a self-contained HTML report, its PNG figures and machine-readable tables.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.table import Table

from probecommit.cli.common import console, err_console, safe, user_errors
from probecommit.cli.output import number, print_table, write_csv
from probecommit.errors import UsageError
from probecommit.store.safefile import output_dir, write_text

def _f(v, signed: bool = False) -> str:
    return number(v, signed)


def _ci(row, name: str, signed: bool = False) -> str:
    return f"{_f(row[name], signed)} [{_f(row[name + '_lo'], signed)}, {_f(row[name + '_hi'], signed)}]"


def _ci3(row, metric: str, arm: str, signed: bool = False) -> str:
    return (f"{_f(row[f'{metric}_{arm}'], signed)} [{_f(row[f'{metric}_lo_{arm}'], signed)}, "
            f"{_f(row[f'{metric}_hi_{arm}'], signed)}]")


def _parse_budgets(text: Optional[str]) -> Optional[list[int]]:
    if not text:
        return None
    try:
        return sorted({int(x) for x in text.replace(" ", "").split(",") if x})
    except ValueError:
        raise UsageError(f"--budgets must be comma-separated integers, got {text!r}") from None


def print_audit_table(table, title: str) -> None:
    """Rich tables of the per-budget audit metrics with intervals, one per method/variant."""
    groups = [c for c in ("method", "variant") if c in table.columns]
    parts = list(table.groupby(groups, sort=False)) if groups else [((), table)]
    for key, part in parts:
        key = key if isinstance(key, tuple) else (key,)
        name = " / ".join(map(safe, key))
        out = Table(title=f"{safe(title)}: {name}" if name else safe(title), title_style="bold")
        for col in ("k", "n", "failed", "coverage", "cluster cov.", "escape", "R_k", "R̂_k", "e_k"):
            out.add_column(col, justify="right")
        for _, row in part.iterrows():
            out.add_row(str(int(row["k"])), str(int(row["n_episodes"])), str(int(row["n_failed"])),
                        _ci(row, "coverage"), _ci(row, "cluster_coverage"), _ci(row, "escape"),
                        _f(row["realized"]), _f(row["predicted"]), _ci(row, "optimism", True))
        print_table(out)


@user_errors
def audit_command(
    path: Path = typer.Argument(..., help="Run directory, a Parquet/CSV episode log, or a robot session log (.jsonl or its directory: Table VII)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output folder (default: <input>-audit/ beside the "
                                       "run directory or log)."),
    resamples: int = typer.Option(2000, min=100, help="Cluster-bootstrap resamples."),
    seed: int = typer.Option(0, help="Bootstrap seed."),
    nominal: float = typer.Option(0.8, min=0.0, max=1.0, help="Nominal coverage drawn in the figure."),
    loss: Optional[str] = typer.Option(None, "--loss", help="The loss kind of a log: 'binary' (failure 0/1) or "
                                       "'continuous' (a miss); default: inferred from the realized column."),
) -> None:
    """Audit coverage, support escape and optimism per budget, with cluster-bootstrap intervals."""
    from probecommit.audit.pipeline import audit
    from probecommit.cli.robot_commands import audit_session_log, is_session_log
    from probecommit.report.audit_report import audit_figure, write_html_report
    from probecommit.report.figures import save_figure

    if is_session_log(path):
        audit_session_log(path, out, resamples, seed)
        return
    result = audit(path, resamples=resamples, seed=seed, loss=loss)
    config_file = path / "config.yaml" if path.is_dir() else None
    if config_file is not None and config_file.is_file():
        from probecommit.store.yamlsafe import load_yaml

        data = load_yaml(config_file.read_bytes(), str(config_file))
        schedule = (((data if isinstance(data, dict) else {}).get("probes") or {}) or {}).get("schedule")
        if schedule == "adaptive":
            from probecommit.cli.common import print_warning

            print_warning("this run's probes were chosen adaptively by its own belief: its episodes are not paired "
                          "with a run of another model on the same instances (other probes would have been chosen)")
    from probecommit.report.vocabulary import default_output

    out = output_dir(out, default_output(path, "audit"))  # created; a symlinked default refused
    print_audit_table(result.table, f"audit of {path}")
    if result.n_failed:
        console.print(f"{result.n_failed} failed row(s) of {result.n_total} excluded from every metric")
    from probecommit.cli.common import print_warning as _warn

    for note in result.notes:
        _warn(note)
    if result.surprise is not None:
        s = Table(title="prequential surprise: AUC for final-budget escape", title_style="bold")
        for col in ("k", "escaped", "not escaped", "AUC"):
            s.add_column(col, justify="right")
        for _, row in result.surprise.iterrows():
            s.add_row(str(row["k"]), str(row["n_escaped"]), str(row["n_covered"]), _ci(row, "auc"))
        print_table(s)
    write_csv(result.table, out / "audit.csv", paper_names=True)
    if result.surprise is not None:
        write_csv(result.surprise, out / "surprise_auc.csv")
    save_figure(audit_figure(result.table, nominal), out / "audit.png")
    images = []
    if path.is_dir() and (path / "probes.parquet").is_file():
        try:  # a belief snapshot of one episode, when the run's model can be rebuilt here
            from probecommit.report.demo import belief_figure

            images.append(("Belief snapshot: one episode's belief after taps 1, 3 and 5", belief_figure(path, out)))
        except Exception:  # noqa: BLE001 - the snapshot is an extra; the audit stands without it
            pass
    report = write_html_report(out / "audit.html", result, title=f"Audit of {path.name}", nominal=nominal, images=images)
    console.print(f"report: {safe(report)}")


@user_errors
def calibrate_command(
    cal: Path = typer.Option(..., "--cal", help="Calibration run directory."),
    test: Path = typer.Option(..., "--test", help="Test run directory (same model and schedule, other instances)."),
    alpha: float = typer.Option(0.2, min=0.001, max=0.999, help="Miscoverage level (1 - alpha is the target)."),
    budgets: Optional[str] = typer.Option(None, help="Comma-separated budgets (default: all)."),
    cost_budget: Optional[int] = typer.Option(None, help="Budget of the failure comparison (default: the last)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output folder (default: <test>-calibration/ beside the test run)."),
    resamples: int = typer.Option(2000, min=100, help="Cluster-bootstrap resamples."),
    seed: int = typer.Option(0, help="Bootstrap seed."),
    plateau: Optional[str] = typer.Option(
        None, help="Set at t = 1: 'prefix' (the paper, with its zero-weight plateau exception) or 'hull' "
                   "(every particle: the conformal guarantee without exception). Default: the runs' config."),
) -> None:
    """Conformal thresholds and margin on --cal; their effect on --test (Tables III and IV)."""
    from probecommit.process.forked import forked_helpers
    from probecommit.process.memory import large_arrays_in_heap
    from probecommit.runner.calibration import calibrate

    if plateau is not None and plateau not in ("prefix", "hull"):
        raise UsageError(f"--plateau must be 'prefix' or 'hull', got {plateau!r}")
    # Two helpers import the report's modules while calibrate runs, then draw its figures beside each other.
    # Its passes keep their large arrays in the heap: reused, not faulted in afresh (docs/decisions.md, "cal3:").
    with forked_helpers(2, warm=_REPORT_MODULES) as helpers:
        with large_arrays_in_heap():
            res = calibrate(cal, test, alpha, _parse_budgets(budgets), cost_budget=cost_budget, resamples=resamples,
                            seed=seed, plateau=plateau)
        _write_calibration(res, cal, test, alpha, out, helpers)


#: What the calibration report draws with (matplotlib), imported by the helpers ahead.
_REPORT_MODULES = ("probecommit.report.audit_report", "probecommit.report.figures")


def _write_calibration(res, cal: Path, test: Path, alpha: float, out: Optional[Path], helpers) -> None:
    """Print Tables III and IV and write the outputs: the figure and the report's two sections are drawn by
    ``helpers`` (or here) while the tables are printed and written."""
    from probecommit.report.vocabulary import default_output

    out = output_dir(out, default_output(test, "calibration"))  # created; a symlinked default refused
    console.print(f"M = {res.n_calibration} calibration instances, 1 - alpha = {1 - alpha:.2f}; "
                  f"simultaneous t = {_f(res.simultaneous_threshold)}; margin gamma = {res.margin.gamma:.2f}"
                  f"{'' if res.margin.satisfied else ' (rule not met on the grid)'}; "
                  f"distribution-free margin = {_f(res.distribution_free_margin)}")
    figure = helpers.submit(_calibration_figure_section, res, 1 - alpha, out / "calibration.png")
    audit = helpers.submit(_audit_section, res.audit_calibrated, 1 - alpha)
    t3 = Table(title="coverage and optimism on test (original -> calibrated)", title_style="bold")
    for col in ("k", "t_k", "cluster cov. original", "cluster cov. calibrated", "e_k original", "e_k calibrated"):
        t3.add_column(col, justify="right")
    for _, r in res.table3.iterrows():
        t3.add_row(str(int(r["k"])), _f(r["threshold"]),
                   _ci3(r, "cluster_coverage", "original"), _ci3(r, "cluster_coverage", "calibrated"),
                   _ci3(r, "optimism", "original", True), _ci3(r, "optimism", "calibrated", True))
    t3.add_row("mean |.|", "", f"{_f(res.summary['mean_abs_cluster_coverage_gap_original'])}",
               f"{_f(res.summary['mean_abs_cluster_coverage_gap_calibrated'])}",
               f"{_f(res.summary['mean_abs_optimism_original'])}", f"{_f(res.summary['mean_abs_optimism_calibrated'])}")
    print_table(t3)
    # "failure" for a binary task, "miss" for a continuous one (the column is the realized loss either way).
    import pandas as pd

    realized = pd.read_parquet(test / "episodes.parquet", columns=["realized"])["realized"].dropna()
    binary = bool(realized.isin([0.0, 1.0]).all())
    loss_name = "failure" if binary else "miss"
    t4 = Table(title=f"cost of calibration: {loss_name} at k = {res.cost_budget}", title_style="bold")
    for col in ("setting", "k", "n", loss_name):
        t4.add_column(col, justify="right")
    for _, r in res.cost.iterrows():
        t4.add_row(safe(r["setting"]), str(int(r["k"])), str(int(r["n_episodes"])), _ci(r, "failure"))
    for _, r in res.cost_differences.iterrows():
        t4.add_row(f"{r['treatment']} - {r['baseline']}", "", str(int(r["n_pairs"])),
                   f"{_f(r['difference'], True)} [{_f(r['lo'], True)}, {_f(r['hi'], True)}] p={r['p_sign_flip']:.3g}")
    print_table(t4)
    write_text(out / "calibration.json", json.dumps(res.to_dict(), indent=2, default=float))
    write_csv(res.table3, out / "table3.csv", paper_names=True)
    write_csv(res.cost, out / "cost.csv")
    write_csv(res.cost_differences, out / "cost_differences.csv")
    write_csv(res.margin.search, out / "margin_search.csv")
    sections = audit.result() + figure.result()
    report = helpers.submit(_write_report, out / "calibration.html", title="Calibration", nominal=1 - alpha,
                            notes=f"calibration run {cal}, test run {test}; the audit table is the calibrated executor's.",
                            sections=sections).result()
    console.print(f"report: {safe(report)}")


def _calibration_figure_section(res, nominal: float, png: Path) -> list[str]:
    """The calibration figure saved (PNG and PDF) and the report's calibration section (a helper's job)."""
    from probecommit.report.audit_report import calibration_figure, calibration_section_html
    from probecommit.report.figures import save_figure

    figure = calibration_figure(res.table3, nominal)
    save_figure(figure, png)
    return calibration_section_html(res, figure)  # the same figure drawn again for the page, not rebuilt


def _audit_section(audit_result, nominal: float) -> list[str]:
    """The report's audit section (a helper's job)."""
    from probecommit.report.audit_report import audit_section_html

    return audit_section_html(audit_result, nominal)


def _write_report(path: Path, **kwargs) -> Path:
    """The report page around sections already drawn (a helper's job: it has matplotlib imported)."""
    from probecommit.report.audit_report import write_html_report

    return write_html_report(path, **kwargs)


@user_errors
def gates_command(
    cal: Path = typer.Option(..., "--cal", help="Calibration run directory."),
    test: Path = typer.Option(..., "--test", help="Test run directory."),
    alpha: float = typer.Option(0.2, min=0.001, max=0.999, help="Miscoverage level of the simultaneous threshold."),
    budgets: Optional[str] = typer.Option(None, help="Comma-separated nested budgets (default: all)."),
    target: float = typer.Option(0.6, min=0.0, max=1.0, help="Commit rate of the operating point."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output folder (default: <test>-gates/ beside the test run)."),
    resamples: int = typer.Option(2000, min=100, help="Bootstrap resamples (surprise AUC)."),
    seed: int = typer.Option(0, help="Bootstrap seed."),
) -> None:
    """Commit gates: failure among committed vs commit rate under first-passage commitment."""
    from probecommit.runner.calibration import gates
    from probecommit.report.audit_report import gates_figure, write_html_report
    from probecommit.report.figures import save_figure

    res = gates(cal, test, alpha, _parse_budgets(budgets), target_rate=target, resamples=resamples, seed=seed)
    from probecommit.report.vocabulary import default_output

    out = output_dir(out, default_output(test, "gates"))  # created; a symlinked default refused
    console.print(f"simultaneous t = {_f(res.info['threshold'])}, margin gamma = {res.info['gamma']:.2f}; "
                  f"{res.n_trajectories} trajectories ({res.n_dropped} dropped), budgets {res.budgets}")
    tab = Table(title=f"gates at the commit rate nearest {target:.0%}", title_style="bold")
    for col in ("signal", "area", "range", "tau", "committed", "escaped in pool", "escaped rejected",
                "claimed", "realized"):
        tab.add_column(col, justify="right")
    for _, r in res.summary.iterrows():
        tab.add_row(safe(r["signal"]) + ("" if r["deployable"] else " (hindsight)"), _f(r["area"]),
                    f"[{_f(r['c_min'])}, {_f(r['c_max'])}]", _f(r.get("tau")),
                    f"{int(r['n_committed'])} ({_f(r['commit_rate'])})",
                    f"{int(r['escaped_committed'])}/{int(r['n_committed'])}",
                    f"{int(r['escaped_rejected'])}/{int(r['n_rejected'])}", _f(r["claimed"]), _f(r["realized"]))
    print_table(tab)
    write_csv(res.curves, out / "gate_curves.csv")
    write_csv(res.summary, out / "gates.csv")
    write_csv(res.info["surprise"], out / "surprise_auc.csv")
    save_figure(gates_figure(res), out / "gates.png")
    report = write_html_report(out / "gates.html", title="Commit gates", gates=res, nominal=1 - alpha,
                               notes=f"calibration run {cal}, test run {test}")
    console.print(f"report: {safe(report)}")


def register(app: typer.Typer) -> None:
    """Register ``audit``, ``calibrate`` and ``gates`` on the main app."""
    app.command("audit")(audit_command)
    app.command("calibrate")(calibrate_command)
    app.command("gates")(gates_command)
