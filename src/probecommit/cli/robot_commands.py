"""Robot sessions on the command line: the stand-in robot, a log's audit (Table VII) and its fault replays."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich import box
from rich.table import Table

from probecommit.cli.output import print_table
from probecommit.cli.common import console, print_warning, progress_bar, safe, user_errors
from probecommit.errors import UsageError

robot_app = typer.Typer(no_args_is_help=True, help="Robot sessions: run the simulated rig, inspect a session log.")


def is_session_log(path: Path) -> bool:
    """A session log: a ``.jsonl`` file, or a directory holding ``session.jsonl``."""
    return (path.is_file() and path.suffix == ".jsonl") or (path.is_dir() and (path / "session.jsonl").is_file())


def _out_dir(path: Path, out: Optional[Path], suffix: str) -> Path:
    folder = path if path.is_dir() else path.parent
    from probecommit.store.safefile import output_dir

    return output_dir(out, folder / suffix)


def _ci(lo: float, hi: float) -> str:
    return f"[{lo:+.2f},{hi:+.2f}]"


def print_robot_table(table, title: str) -> None:
    """Table VII in 80 columns."""
    t = Table(title=title, title_style="bold", box=box.SIMPLE_HEAD, padding=(0, 1), pad_edge=False)
    for col in ("taps", "n", "in win", "entered", "pred", "real", "optim", "95% CI", "cover", "aim mm"):
        t.add_column(col, justify="right", no_wrap=True)
    for r in table.itertuples(index=False):
        entered = "-" if r.entered != r.entered else str(int(r.entered))
        t.add_row(str(int(r.taps)), str(int(r.episodes)), str(int(r.in_window)), entered, f"{r.predicted:.3f}",
                  f"{r.realized:.3f}", f"{r.optimism:+.3f}", _ci(r.optimism_lo, r.optimism_hi),
                  f"{int(r.covered)}/{int(r.episodes)}", f"{r.aim_error:.1f}")
    print_table(t)


def audit_session_log(path: Path, out: Optional[Path], resamples: int, seed: int) -> None:
    """``probecommit audit LOG`` for a session log: Table VII, Fig. 5b, CSVs."""
    import numpy as np

    from probecommit.cli.output import write_csv
    from probecommit.report.figures import save_figure
    from probecommit.report.robot_figures import aim_error_figure
    from probecommit.robot.session import load_session
    from probecommit.robot.table import robot_table, session_episodes
    from probecommit.runner.build import build_model

    result = session_episodes(path)
    table = robot_table(result.rows, resamples=resamples, seed=seed)
    print_robot_table(table, f"robot audit of {result.path} (optimism: cluster bootstrap over positions)")
    covered = int(result.rows["covered"].sum())
    console.print(f"coverage {covered} of {len(result.rows)}; support escape "
                  f"{int(result.rows['escaped'].sum())} of {len(result.rows)}; "
                  f"{result.rows['instance_id'].nunique()} positions")
    for note in result.notes:
        print_warning(note)
    from probecommit.report.vocabulary import MIN_CLUSTERS, default_output

    target = out or default_output(path, "audit")
    target.mkdir(parents=True, exist_ok=True)
    positions = int(result.rows["instance_id"].nunique())
    few = []
    if positions < MIN_CLUSTERS:
        few.append(f"Intervals here rest on {positions} positions (the clusters), fewer than {MIN_CLUSTERS}: a cluster "
                   "bootstrap over so few is too coarse to be evidence.")
        print_warning(few[0])
    write_csv(table, target / "robot_table.csv", paper_names=True)
    write_csv(result.rows, target / "episodes.csv")
    from probecommit.tasks.registry import get as get_family

    config, *_ = load_session(path)
    model = build_model(config)
    window = half = None
    nominal = (np.asarray(model.prior_low, float) + np.asarray(model.prior_high, float)) / 2
    interval = model.with_margin(1.0).success_interval(nominal[None, :])  # None: no 1-D success window
    if interval is not None:
        window = float((interval[1] - interval[0])[0] / 2)
    guides = get_family(config.family).figure_guides
    if guides is not None:
        half = guides(model).get("half_gap")
    png = save_figure(aim_error_figure(result.rows, window, half), target / "aim_error.png")
    from probecommit.report.audit_report import write_html_report

    report = write_html_report(
        target / "audit.html", title=f"Robot audit of {Path(result.path).name}", warnings=few + list(result.notes),
        notes=f"{len(result.rows)} episodes at {positions} positions; coverage {covered} of {len(result.rows)}; "
              "optimism intervals: cluster bootstrap over positions.",
        tables=[("Per budget: predicted R̂ₖ, realized Rₖ, optimism eₖ, coverage", table)],
        images=[("Aim error against taps (filled: entered)", png)])
    console.print(f"table: {safe(target / 'robot_table.csv')}; figure: {safe(png)}; report: {safe(report)}")


def replay_session_log(path: Path, fault: Optional[str], sweep: Optional[str], half_width: Optional[float],
                       out: Optional[Path], resamples: int, seed: int) -> None:
    """``probecommit replay LOG [--fault ...]``: as deployed, or a fault sweep (Fig. 5c/5d)."""
    from probecommit.cli.output import write_csv
    from probecommit.report.figures import save_figure
    from probecommit.report.robot_figures import fault_sweep_figure
    from probecommit.robot.replay import fault_sweep, parse_sweep, replay_session
    from probecommit.robot.table import robot_table

    if fault is None:
        if sweep is not None or half_width is not None:
            raise UsageError("--sweep and --half-width need --fault boundary or --fault prior")
        result, reproduced = replay_session(path)
        print_robot_table(robot_table(result.rows, resamples=resamples, seed=seed), f"replay of {result.path} as deployed")
        console.print(f"recorded decisions reproduced: {reproduced:.3f} of episodes")
        if reproduced < 1:
            print_warning("the replay as deployed did not reproduce every recorded decision: the log was written "
                          "by another version of the code or model (see docs/robot.md)")
        return
    if fault == "boundary":
        if half_width is not None:
            raise UsageError("--half-width is for --fault prior; the boundary fault takes --sweep START:STOP:STEP")
        sizes = parse_sweep(sweep or "0:14:1")
        xlabel, reference, ref_label = "boundary pulled inward (mm)", 2.1 * 3.86, "sim. 2.1 mm error at rig scale"
    elif fault == "prior":
        if half_width is not None and sweep is not None:
            raise UsageError("give --half-width or --sweep for the prior fault, not both")
        sizes = [half_width] if half_width is not None else parse_sweep(sweep or "38.6,30,24,18,12,8")
        xlabel, reference, ref_label = "prior half-width (mm)", None, ""
    else:
        raise UsageError(f"unknown fault {fault!r}; faults: boundary, prior")
    bar, update = progress_bar(f"replay under {fault} fault")
    done = {"n": 0}

    def step(_size: float) -> None:
        done["n"] += 1
        update(done["n"], len(sizes))

    with bar:
        table, reproduced = fault_sweep(path, fault, sizes, resamples=resamples, seed=seed, progress=step)
    t = Table(title=f"{fault} fault replayed on {path.name} (paired over positions)", title_style="bold",
              box=box.SIMPLE_HEAD, padding=(0, 1), pad_edge=False)
    for col in ("size", "cover", "escape", "optim", "d optim", "95% CI", "d cover", "95% CI "):
        t.add_column(col, justify="right", no_wrap=True)
    for r in table.itertuples(index=False):
        t.add_row(f"{r.size:g}", f"{r.coverage:.3f}", f"{r.escape:.3f}", f"{r.optimism:+.3f}",
                  f"{r.delta_optimism:+.3f}" + ("*" if r.optimism_resolved else " "), _ci(r.delta_optimism_lo, r.delta_optimism_hi),
                  f"{r.delta_coverage:+.3f}" + ("*" if r.coverage_resolved else " "), _ci(r.delta_coverage_lo, r.delta_coverage_hi))
    print_table(t)
    console.print("* resolved: the interval excludes zero. Deployed replay reproduced "
                  f"{reproduced:.3f} of the recorded decisions.")
    target = _out_dir(path, out, "replay")
    write_csv(table, target / f"fault_{fault}.csv")
    png = None
    if len(table) > 1:
        png = save_figure(fault_sweep_figure(table, xlabel, reference, ref_label), target / f"fault_{fault}.png")
    console.print(f"table: {safe(target / f'fault_{fault}.csv')}" + (f"; figure: {safe(png)}" if png else ""))


@robot_app.command("simulate")
@user_errors
def simulate(
    config: Optional[Path] = typer.Argument(None, help="Study config of the rig (default: the frozen configs/paper/rig.yaml)."),
    out: Path = typer.Option(Path("runs/rig-session"), "--out", "-o", help="Session log directory (resumed if it exists)."),
    stop_after: Optional[int] = typer.Option(None, "--stop-after", min=1, help="Stop after this many episodes (resume later)."),
    repair: bool = typer.Option(False, "--repair", help="Resume a log whose last line a crash cut off (the line is "
                                "moved, byte for byte, to session.jsonl.partial)."),
) -> None:
    """Run the simulated rig (the stand-in robot) through a Session, writing a session log.

    Then: 'probecommit audit OUT' (Table VII) and 'probecommit replay OUT --fault boundary'.
    """
    from probecommit.robot.simulated import simulate_session
    from probecommit.studies.robot import rig_config  # the paper's rig protocol: a study names its family

    bar, update = progress_bar("simulated rig: episodes")
    with bar:
        log = simulate_session(out, config or rig_config(), progress=update, stop_after=stop_after, repair=repair)
    console.print(f"session log: {safe(log)}")
    console.print(f"next: probecommit audit {safe(out)}   |   probecommit replay {safe(out)} --fault boundary")


@robot_app.command("show")
@user_errors
def show(log: Path = typer.Argument(..., help="Session log (.jsonl) or its directory.")) -> None:
    """Summarize a session log: episodes, positions, truths, what is still open."""
    from probecommit.robot.session import load_session

    config, episodes, truths, path = load_session(log)
    decided = sum(ep.decision is not None for ep in episodes.values())
    done = sum(ep.done for ep in episodes.values())
    positions = sorted({ep.position for ep in episodes.values()})
    console.print(f"{safe(path)}: task {config.family}, {len(episodes)} episode(s) ({decided} committed, {done} with an "
                  f"outcome) at {len(positions)} position(s); truths recorded for {len(truths)}")
    missing = [p for p in positions if p not in truths]
    if missing:
        print_warning(f"no truth yet for position(s) {', '.join(missing[:10])}: record_truth() them before the audit")
    open_eps = [ep for ep in episodes.values() if not ep.done]
    for ep in open_eps:
        console.print(f"open: episode {ep.episode} at {safe(ep.position)}, {len(ep.probes)} of {ep.taps} taps"
                      f"{', committed' if ep.decision else ''}")


def register(app: typer.Typer) -> None:
    app.add_typer(robot_app, name="robot")
