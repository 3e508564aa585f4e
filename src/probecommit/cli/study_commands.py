"""Study commands: reproduce, scan, faults."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from probecommit.store.safefile import output_dir, write_text, write_with
from probecommit.cli.common import console, err_console, progress_bar, safe, user_errors
from probecommit.errors import UsageError

REPO_ROOT = Path(__file__).resolve().parents[3]


def _paper_delta_mm() -> float:
    """The paper's tap-boundary offset, read when a command runs (importing the insertion family
    at start-up would cost every command, ``--help`` included, its model and config imports)."""
    from probecommit.tasks.insertion.model import PAPER_DELTA_MM

    return PAPER_DELTA_MM


def _stepper():
    """A progress callback that shows one bar per named step."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn("{task.description}", style="bold", markup=False), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   console=err_console)
    tasks: dict[str, int] = {}

    def update(step: str, done: int, total: int) -> None:
        if step not in tasks:
            tasks[step] = bar.add_task(step, total=total)
        bar.update(tasks[step], completed=done, total=total)

    return bar, update


def reproduce(
    targets: Optional[list[str]] = typer.Argument(None, help="Targets: insertion, breadth, beyond, all, or a paper item in the paper's numbering such as table-5 or tab:testc (see --list)."),
    list_targets: bool = typer.Option(False, "--list", help="List every target and the tables and figures it makes."),
    quick: bool = typer.Option(False, "--quick", help="The same pipelines on a few instances (minutes; for CI)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Root for run directories and results (default runs/paper[-quick])."),
    workers: int = typer.Option(1, "--workers", "-w", min=1, help="Local worker processes for the rollouts."),
    families: Optional[str] = typer.Option(None, "--families", help="breadth only: comma-separated families (default: all of them)."),
    publish: Optional[bool] = typer.Option(None, help="Copy results into results/paper/ and rewrite REPRODUCTION.md (default: yes for full runs, no with --quick or a --families subset)."),
    publish_to: Optional[Path] = typer.Option(None, "--publish-to", help="Publish into this folder instead of the checkout (DIR/results/paper and DIR/REPRODUCTION.md); `probecommit verify DIR` checks it."),
) -> None:
    """Regenerate the paper's tables and figures from the frozen configs in configs/paper/.

    A killed reproduction resumes: rerun the same command and finished runs are kept.
    """
    from probecommit.cli.common import safe as escape
    from rich.table import Table

    from probecommit.report import paper

    if list_targets:
        table = Table(title="reproduce targets", title_style="bold")
        for col in ("target", "makes", "runs first"):
            table.add_column(col)
        for row in paper.listing():
            table.add_row(*map(escape, row))
        console.print(table)
        return
    names = targets or ["insertion"]
    paper.resolve(names)  # an unknown target fails before anything runs
    root = out or Path("runs") / ("paper-quick" if quick else "paper")
    bar, update = _stepper()
    with bar:
        options = {"families": [f.strip() for f in families.split(",") if f.strip()]} if families else {}
        done = paper.reproduce(names, root, quick=quick, progress=update, workers=workers, options=options)
    for name, folder in done["targets"].items():
        console.print(f"{escape(name)}: {escape(str(folder))}  (wall {done['wall_s'][name] / 60:.1f} min)")
    # A family subset would replace the frozen Table II with a partial one: published only on request.
    if publish_to is not None or (publish if publish is not None else not (quick or families)):
        from probecommit.report.publish import publish as publish_results

        published = publish_results(done["targets"], publish_to or REPO_ROOT, timing=done)
        console.print(f"frozen results: {escape(str(published))}; "
                      f"{escape(str(published.parent.parent / 'REPRODUCTION.md'))} rewritten")


def scan(
    engine: str = typer.Option("mujoco", help="Engine to scan: mujoco, pybullet, sapien or analytic."),
    protocol: Path = typer.Option(REPO_ROOT / "configs" / "paper" / "insertion.yaml", help="Frozen protocol config."),
    step: Optional[float] = typer.Option(None, min=0.001, help="Grid step (mm); default from the protocol (0.25)."),
    boundary_offset: float = typer.Option(default_factory=lambda: _paper_delta_mm(), show_default="the paper's delta",
                                          help="Analytic engine only: its planted boundary offset (mm)."),
    capture: bool = typer.Option(False, "--capture", help="Also scan the capture window (peg entry against lateral offset)."),
    out: Path = typer.Option(Path("runs/scan"), "--out", "-o", help="Output folder for scan.parquet and the figure."),
) -> None:
    """Scan the tap reading against lateral offset on the development truths and fit delta (any engine)."""
    from probecommit.report.study_figures import scan_figure
    from probecommit.studies.protocol import load_protocol
    from probecommit.studies.scan import scan_development

    from probecommit.tasks.registry import get

    engines = get("insertion").engines
    if engine not in engines:
        raise UsageError(f"scan --engine must be one of {', '.join(engines)}, got {engine!r}")
    p = load_protocol(protocol)
    from probecommit.tasks.insertion import make_simulator

    sim = make_simulator(engine, boundary_offset=boundary_offset)  # the offset applies to 'analytic' only
    bar, update = progress_bar("scanning development truths")
    with bar:
        update(0, 1)
        result = scan_development(p, sim, step)
        update(1, 1)
    out = output_dir(out, out)
    write_with(out / "scan.parquet", result.scans.to_parquet)
    summary = result.summary()
    fig = scan_figure(result.grid, result.scans, str(result.scans.instance_id.iloc[0]), summary["delta"], out / "scan_section.png")
    write_text(out / "scan_summary.json", json.dumps(summary, indent=2))
    console.print(f"{engine}: delta = {summary['delta']:+.4f} mm (SD {summary['sd']:.4f}, min {summary['min']:+.4f}, "
                  f"max {summary['max']:+.4f}) over {summary['scans']} scans; boundary moves "
                  f"{summary['shift_vs_deployed_mm']:.3f} mm from the deployed hg - r; engine calls {sim.engine_calls}")
    console.print(f"scans: {safe(out / 'scan.parquet')}; figure: {safe(fig)}")
    if capture:
        from probecommit.runner.build import build_model
        from probecommit.runner.instances import draw_instances
        from probecommit.studies.engines import scan_capture_window

        cfg = p.run_config("development", "development", "development", "random")
        window = scan_capture_window(sim, draw_instances(cfg, build_model(cfg)))
        write_with(out / "capture.parquet", window.truths.to_parquet)
        c = window.summary()
        console.print(f"{engine}: capture window / w(c) = {c['ratio_mean']:.3f} (SD {c['ratio_sd']:.3f} over the "
                      f"development truths); per truth: {safe(out / 'capture.parquet')}")


def engines_check(
    engines: str = typer.Option("mujoco,pybullet,sapien", help="Comma-separated engines to compare."),
    tolerance: float = typer.Option(0.5, min=0.0, help="Largest |value - expected| that agrees (mm)."),
) -> None:
    """The same hand queries on every engine (taps over the plate, the slot centre, the chamfer;
    pegs centred, 1 mm and 3 mm off), and where they agree with the scene's design."""
    from probecommit.cli.common import safe as escape
    from rich.table import Table

    from probecommit.studies.engines import check_engines

    names = [e.strip() for e in engines.split(",") if e.strip()]
    table = check_engines(names, tolerance=tolerance)
    out = Table(title=f"engine check (agree = every engine within {tolerance:g} mm of the design)", title_style="bold")
    for col in ["query", "expected", *names, "agree"]:
        out.add_column(col, justify="right" if col not in ("query",) else "left")
    for _, row in table.iterrows():
        out.add_row(escape(str(row["query"])), f"{row['expected']:+.3f}", *[f"{row[n]:+.3f}" for n in names],
                    "yes" if row["agree"] else f"NO ({escape(row['disagreeing'])})")
    console.print(out)
    if not table["agree"].all():
        raise typer.Exit(1)


def faults(
    base: Path = typer.Argument(..., help="Run directory of the base rollout (corrected model, random probes)."),
    noise_run: Optional[Path] = typer.Option(None, help="Run with simulator noise x4 (same instances and seed)."),
    prior_run: Optional[Path] = typer.Option(None, help="Run with truths from +-12 mm (same seed)."),
    protocol: Path = typer.Option(REPO_ROOT / "configs" / "paper" / "insertion.yaml", help="Frozen protocol config."),
    out: Path = typer.Option(Path("runs/faults"), "--out", "-o", help="Output folder."),
) -> None:
    """Inject the five mismatch classes on stored probes, with known fixes and tempering."""
    from probecommit.report.study_figures import fault_signatures
    from probecommit.runner.replay import load_run
    from probecommit.studies.faults import fault_arms, run_fault_harness, signature_table
    from probecommit.studies.protocol import load_protocol

    p = load_protocol(protocol)
    f = p.faults
    rollouts = {"base": load_run(base)}
    if noise_run:
        rollouts["noise"] = load_run(noise_run)
    if prior_run:
        rollouts["prior"] = load_run(prior_run)
    every_arm = fault_arms(f.noise_factor, f.prior_half_width, f.particles, f.frame_offset, f.temperature, p.sigma)
    arms = [a for a in every_arm if a.rollout in rollouts]
    skipped = sorted({a.fault for a in every_arm} - {a.fault for a in arms})
    bar, update = progress_bar("fault arms")
    with bar:
        episodes = run_fault_harness(rollouts, arms, progress=update)
    out = output_dir(out, out)
    write_with(out / "faults_episodes.parquet", episodes.to_parquet)
    probe = episodes[(episodes.method == "probe_robust") & (episodes.status == "ok")]
    kmax = int(probe.k.max())
    summary = (probe[probe.k == kmax].assign(optimism=lambda d: d.realized - d.predicted)
               .groupby(["fault", "arm"], sort=False)[["realized", "optimism", "covered", "escaped"]].mean())
    console.print(summary.rename(columns={"realized": "failure", "covered": "coverage", "escaped": "escape"}).round(3).to_string())
    fig = fault_signatures(signature_table(episodes), out / "fault_signatures.png")
    if skipped:
        err_console.print(f"skipped faults needing other rollouts: {', '.join(skipped)} (pass --noise-run / --prior-run)")
    console.print(f"episodes: {safe(out / 'faults_episodes.parquet')}; figure: {safe(fig)}")


def verify(
    results: Path = typer.Argument(REPO_ROOT / "results", help="A publication: results/, results/paper, or a --publish-to folder."),
    notes: bool = typer.Option(False, "--notes", help="Also list what is traced only (files not rendered again, figures without stored data)."),
) -> None:
    """Recompute the published numbers from the stored episode tables and render every published file again."""
    from probecommit.cli.common import safe as escape

    from probecommit.report.verify import verify as run_verify

    report = run_verify(results)
    if notes:
        for line in report.notes:
            console.print(escape(f"traced only: {line}"))
    for line in report.failures:
        err_console.print(f"FAILED {escape(line)}")
    console.print(escape(report.summary()))
    if not report.ok:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("reproduce")(user_errors(reproduce))
    app.command("scan")(user_errors(scan))
    app.command("faults")(user_errors(faults))
    app.command("verify")(user_errors(verify))
    engines_app = typer.Typer(help="Cross-engine checks of the insertion scene (MuJoCo, PyBullet, SAPIEN).", no_args_is_help=True)
    engines_app.command("check")(user_errors(engines_check))
    app.add_typer(engines_app, name="engines")
