"""The ``probecommit`` command line (typer + rich)."""

from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path
from typing import Optional

import typer
from rich import box
from probecommit.cli.common import safe as escape
from rich.table import Table

from probecommit.cli import help_format  # noqa: F401 - flags shown as flags in --help
from probecommit.cli.common import console, err_console, print_warning, progress_bar, safe, user_errors
from probecommit.errors import UsageError

app = typer.Typer(
    no_args_is_help=True,
    help="Probe a few times, commit once, audit offline. Run 'probecommit COMMAND --help' for each command.",
)


def _print_version(value: bool) -> None:
    if value:
        from probecommit.cli.diagnostics import version_text

        console.print(safe(version_text()), highlight=False)
        raise typer.Exit()


@app.callback()
def main_options(
    version: bool = typer.Option(False, "--version", is_eager=True, callback=_print_version,
                                 help="Print the version, the code's identity (git commit) and the engines found."),
    verbose: int = typer.Option(0, "--verbose", "-v", count=True, show_default=False, help="Log progress to stderr (-v: info, -vv: debug)."),
    debug: bool = typer.Option(False, "--debug", help="Debug logging, and the traceback of an internal error."),
) -> None:
    """Probe a few times, commit once, audit offline."""
    from probecommit.cli.diagnostics import configure_logging

    configure_logging(verbose, debug)


def _summary_rows(episodes) -> tuple[list, bool]:
    """The per-budget rows of an episodes table (a DataFrame, or a run's Arrow table, read with NumPy:
    a run's process never imports pandas) and whether its outcomes are 0/1."""
    from probecommit.report.tables import budget_rows, summary_columns

    columns = summary_columns(episodes)
    realized = columns["realized"]  # (np.unique would import numpy.ma: 10 ms)
    return budget_rows(columns), set(realized[realized == realized].tolist()) <= {0.0, 1.0}


def print_budget_table(episodes, title: str) -> None:
    rows, binary = _summary_rows(episodes)
    # Short headers and labels: the table must fit 80 columns (pipes and CI logs).
    headers = ("method", "k", "n", "failure" if binary else "miss", "pred", "e_k", "cover", "escape", "failed")
    labels = {"blind_bayes": "Blind-Bayes", "blind_robust": "Blind-Robust", "probe_robust": "Probe-Robust"}
    table = Table(title=title, title_style="bold", box=box.SIMPLE_HEAD, padding=(0, 1), pad_edge=False)
    for col in headers:
        table.add_column(col, justify="right", no_wrap=True, min_width={"method": 12, "n": 3}.get(col, len(col)))
    for row in rows:
        table.add_row(
            labels.get(str(row["method"]), safe(row["method"])), str(row["k"]), str(row["episodes"]),
            f"{row['failure']:.3f}", f"{row['predicted']:.3f}", f"{row['optimism']:+.3f}",
            f"{row['coverage']:.3f}", f"{row['escape']:.3f}", str(row["failed"]),
        )
    console.print(table)


def _run(config, out: Path, workers: int, ray: Optional[str], threads: Optional[int] = None):
    from probecommit.runner.study import RunParts, choose_backend, preflight, run_concurrency, run_study
    from probecommit.store.rundir import RunDir
    from probecommit.runner.config import dump_config

    workers, threads, why = choose_backend(config, workers, ray, threads)
    if why:
        err_console.print(safe(why), highlight=False)

    # Fail on a bad config, too little memory for the run at its concurrency, or an incompatible
    # directory before drawing a progress bar; the model and executors built for it are the run's.
    parts = RunParts.build(config)
    instances = preflight(config, run_concurrency(config, workers, ray, threads), parts)
    RunDir(out).check_writable(dump_config(config))
    bar, update = progress_bar(f"{config.name}: units")
    with bar:
        return run_study(config, out, workers=workers, ray_address=ray, progress=update, threads=threads,
                         parts=parts, instances=instances)


def warn_failed(result) -> None:
    """One warning line when some episodes failed (engine NaN or error), else nothing; and one
    when some beliefs lost every particle (the likelihood ruled all of them out)."""
    resets = result.belief_reset_rows
    if resets:
        print_warning(f"{resets} episode row(s) had a belief that lost every particle (every particle impossible "
                      "under the likelihood; weights reset to uniform): see the 'belief_resets' column; is sigma too small?")
    failed = result.failed_episodes
    if failed:
        trajectories = result.manifest.get("failed_trajectories", 0)
        print_warning(
            f"{failed} of {result.episodes_table.num_rows} episode rows failed ({trajectories} trajectories lost in rollout): "
            "the engine returned NaN or raised; see the 'status' and 'error' columns of "
            f"{result.run_dir / 'episodes.parquet'}"
        )


@app.command()
@user_errors
def run(
    config: Path = typer.Argument(..., help="Study config (YAML)."),
    overrides: Optional[list[str]] = typer.Argument(
        None, metavar="KEY=VALUE",
        help="Override config fields (dotted keys, YAML values), e.g. model.sigma=0.4 instances.count=8; validated as the file is."),
    sweep: list[str] = typer.Option(
        [], "--sweep", "-m",
        help="KEY=A,B,C: one run per value (repeat for a grid), each in its own directory under runs/<name>-sweep/ (or --out)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Run directory (default runs/<name>)."),
    workers: int = typer.Option(1, "--workers", "-w", min=1, help="Local worker processes (with --ray local: Ray CPUs)."),
    ray: Optional[str] = typer.Option(
        None, "--ray", help="Run on Ray: 'auto' (an existing cluster), host:port, or 'local' (start one here)."
    ),
    threads: Optional[int] = typer.Option(
        None, "--threads", "-t", min=1,
        help="Units run in this many threads of one process (thread-safe simulators: analytic, MuJoCo insertion; "
             "default: $PROBECOMMIT_ENGINE_THREADS, else the CPUs up to 4; 1: one after the other).",
    ),
) -> None:
    """Run (or resume) a study into a run directory.

    Rerunning the same command after an interruption (Ctrl-C, a crash, SIGKILL)
    keeps the finished units and redoes the rest; results are identical to an
    uninterrupted run, whatever --workers, --threads or --ray.

    KEY=VALUE arguments override fields of the file: config.yaml in the run
    directory is the result, overrides.yaml lists the overrides. --sweep runs
    a grid, one run directory per point, and prints a summary table.
    """
    from probecommit.cli.runs_commands import run_config_with_overrides

    def one_run(cfg, run_dir: Path, title: str):
        result = _run(cfg, run_dir, workers, ray, threads)
        print_budget_table(result.episodes_table, title)
        warn_failed(result)
        console.print(f"run directory: {safe(result.run_dir)}")
        return result

    run_config_with_overrides(config, list(overrides or []), sweep, out, one_run)


@app.command()
@user_errors
def demo(
    out: Path = typer.Option(Path("runs/demo"), "--out", "-o", help="Run directory."),
    workers: int = typer.Option(1, "--workers", "-w", min=1, help="Local worker processes."),
    engine: str = typer.Option("mujoco", help="Ground-truth engine: mujoco or analytic."),
) -> None:
    """Run the embedded default insertion study and write its report."""
    from probecommit.report.demo import write_demo_report
    from probecommit.runner.config import parse_config
    from probecommit.store.yamlsafe import load_yaml

    data = load_yaml(resources.files("probecommit").joinpath("configs/demo.yaml").read_text(), "configs/demo.yaml")
    data["simulator"]["engine"] = engine
    cfg = parse_config(data)
    result = _run(cfg, out, workers, None)
    print_budget_table(result.episodes, "demo: insertion, random taps, deployed tap model")
    warn_failed(result)
    report = write_demo_report(result.run_dir)
    from probecommit.cli.runs_commands import print_demo_reading

    print_demo_reading(result.episodes, out, cfg.model.boundary)
    console.print(f"run directory: {safe(result.run_dir)}")
    console.print(f"report: {safe(report)}")


@app.command()
@user_errors
def replay(
    run_dir: Path = typer.Argument(..., help="A complete run directory, or a robot session log (.jsonl or its directory)."),
    model: Optional[str] = typer.Option(None, "--model", help="Insertion shorthand for --set model.boundary=...: deployed or corrected."),
    delta: Optional[float] = typer.Option(None, help="Insertion shorthand for --set model.delta=... (mm)."),
    set_: list[str] = typer.Option([], "--set", help="Override a model, belief or simulator.aim_offset field: SECTION.FIELD=VALUE (YAML value; repeatable)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="New run directory (default RUN-replay or RUN-<model>)."),
    fixed_probes: bool = typer.Option(False, "--fixed-probes", help="Replay an adaptive run's probes under another model anyway (not a paired comparison)."),
    fault: Optional[str] = typer.Option(None, "--fault", help="Session logs: inject a fault, 'boundary' (tap boundary pulled inward) or 'prior' (prior narrowed)."),
    sweep: Optional[str] = typer.Option(None, "--sweep", help="Session logs: fault sizes START:STOP:STEP in mm (inclusive) or a comma list; boundary default 0:14:1."),
    half_width: Optional[float] = typer.Option(None, "--half-width", help="Session logs, --fault prior: the narrowed prior's half-width (mm)."),
    resamples: int = typer.Option(2000, min=100, help="Session logs: cluster-bootstrap resamples."),
) -> None:
    """Recompute beliefs and episodes from stored probes under another model.

    Both runs then hold identical probes, so their episodes are paired. With no
    option, an insertion run is replayed under the corrected tap model, and a run of
    another family as deployed (it must reproduce its episodes). A robot
    session log is replayed as deployed (it must reproduce its own decisions), or
    under an injected fault with --fault (paper Fig. 5c, 5d).
    """
    from probecommit.cli.robot_commands import is_session_log, replay_session_log
    from probecommit.store.yamlsafe import load_yaml

    if is_session_log(run_dir):
        if model is not None or delta is not None or set_ or fixed_probes:
            raise UsageError("a session log takes --fault/--sweep/--half-width; --model, --delta, --set and "
                             "--fixed-probes are for run directories")
        replay_session_log(run_dir, fault, sweep, half_width, out, resamples, 0)
        return
    if fault is not None or sweep is not None or half_width is not None:
        raise UsageError(f"--fault, --sweep and --half-width replay robot session logs; {run_dir} is not one "
                         "(for a run directory use --set model.FIELD=VALUE)")

    from probecommit.runner.replay import load_run, replay_run

    overrides: dict = {}
    for item in set_:
        key, eq, value = item.partition("=")
        section, dot, field = key.strip().partition(".")
        if not (eq and dot and section and field):
            raise UsageError(f"--set expects SECTION.FIELD=VALUE (e.g. model.sigma=0.4), got {item!r}")
        overrides.setdefault(section, {})[field] = load_yaml(value, f"--set {key.strip()}")
    if model is not None or delta is not None or not overrides:
        from probecommit.runner.replay import load_run as _load

        from probecommit.tasks.registry import families

        family = _load(run_dir).config.family
        short = families()[family].replay_shorthands  # the family names its --model/--delta fields
        if short:
            overrides.setdefault("model", {})[short["model"]] = model or short["model_default"]
            if delta is not None:
                overrides["model"][short["delta"]] = delta
        elif model is not None or delta is not None:
            owners = ", ".join(sorted(n for n, spec in families().items() if spec.replay_shorthands)) or "no family's"
            raise UsageError(f"--model and --delta are {owners} shorthands; {run_dir} is a {family!r} run: use "
                             "--set model.FIELD=VALUE")
        # Another family with no option: replayed as deployed (its episodes must come back identical).
    label = overrides.get("model", {}).get("boundary", "replay")
    target = out or run_dir.with_name(f"{run_dir.name}-{label}")
    path = replay_run(run_dir, target, overrides, fixed_probes=fixed_probes)
    print_budget_table(load_run(path).episodes, f"replay of {run_dir.name} ({', '.join(f'{s}.{k}' for s, v in overrides.items() for k in v)})")
    console.print(f"run directory: {safe(path)}")
    console.print(f"compare: probecommit runs compare {safe(run_dir.as_posix())} {safe(Path(path).as_posix())}",
                  highlight=False)


@app.command()
@user_errors
def tasks(
    check: Optional[str] = typer.Option(None, "--check", metavar="NAME",
                                        help="Run check_family on family NAME (each failure names the declaration to fix)."),
) -> None:
    """List every registered task family: engines, latents, probe, action, sigma, budgets (Table I)."""
    if check is not None:
        from probecommit.cli.check_command import check_command

        check_command(check)
        return

    from probecommit.runner.family_check import ENGINE_EXTRAS, installed
    from probecommit.tasks.registry import families

    table = Table(title="registered task families", title_style="bold", box=box.SIMPLE_HEAD, padding=(0, 1))
    for col in ("family", "engines", "latents", "probe / action", "dims p/m/a", "sigma", "budgets", "metric"):
        table.add_column(col)
    for name, spec in sorted(families().items()):
        model = spec.build_model(spec.config())
        engines = []
        for engine in spec.engines:
            # An engine whose package is missing is shown with the extra that installs it (one rule: check_family's).
            engines.append(engine if installed(engine) else f"{engine} (pip install 'probecommit[{ENGINE_EXTRAS[engine]}]')")
        s = spec.summary
        table.add_row(
            escape(name), escape(", ".join(engines)), escape(", ".join(model.latent_names)),
            escape(f"{s.get('probe', '?')} / {s.get('action', '?')}"),
            f"{model.probe_dim}/{model.observation_dim}/{model.action_dim}",
            escape(s.get("sigma", f"{model.sigma:g}")), escape(s.get("budgets", "")), escape(s.get("metric", "")),
        )
    from probecommit.cli.output import print_table

    print_table(table)  # whole rows in pipes and CI logs


def register_optional_commands() -> None:
    """Register command groups that live in their own modules, if present."""
    from probecommit.cli import study_commands

    study_commands.register(app)
    from probecommit.cli import robot_commands

    robot_commands.register(app)
    from probecommit.cli import runs_commands

    runs_commands.register(app)
    try:
        from probecommit.cli import audit_commands
    except ImportError:
        return
    audit_commands.register(app)


register_optional_commands()


#: pyarrow's default memory pool, unless the user chose one (its own environment variable).
ARROW_POOL_ENV = "ARROW_DEFAULT_MEMORY_POOL"


def use_system_arrow_pool() -> None:
    """Make the command's Arrow buffers come from the C allocator (``ARROW_DEFAULT_MEMORY_POOL=system``),
    unless the variable is already set.

    probecommit's tables are small and short-lived; mimalloc (pyarrow's default) keeps
    reserved segments that cost 20-35 MB of peak memory in a replay here. Set in the
    command, not on import: a program that imports probecommit keeps its own choice.
    Spawned workers inherit it.
    """
    import os

    os.environ.setdefault(ARROW_POOL_ENV, "system")


def main() -> None:  # pragma: no cover - entry point
    """The ``probecommit`` command: the app, then the process ends without the interpreter's
    teardown (:func:`probecommit.process.finish.exit_process`; an uncaught error ends as usual)."""
    from probecommit.process.collector import defer_collection
    from probecommit.process.finish import exit_process
    from probecommit.process.memory import reuse_freed_arrays

    defer_collection()  # until the work begins (the progress bar): process/collector.py
    use_system_arrow_pool()
    reuse_freed_arrays()
    try:
        app()
    except SystemExit as done:  # how the app always ends (typer's standalone mode)
        exit_process(done.code)
    exit_process(0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
