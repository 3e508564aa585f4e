"""One command for the paper: ``probecommit reproduce all`` and its targets.

Each target runs its studies from the frozen configs in ``configs/paper/`` into
``<root>/<target>/`` (run directories resume, so a killed reproduction picks up where
it stopped) and writes its results folder: ``results.json`` (every number the tables
print), each table as Markdown and LaTeX, each figure as PNG and PDF. ``publish``
copies the results into the repository's ``results/paper/<target>/`` with a
``MANIFEST.json`` of hashes (what ``probecommit verify`` checks) and rewrites
``REPRODUCTION.md`` and ``results/paper/report.html``.
"""

from __future__ import annotations

import json
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

import probecommit.report.style  # noqa: F401  (every target's figures in one style, whichever ran first)
from probecommit.tasks.base import shared_engine_answers
from probecommit.errors import UsageError
from probecommit.store.safefile import write_text, write_with

Progress = Callable[[str, int, int], None]


def _noop(step: str, done: int, total: int) -> None:
    return None


@dataclass(frozen=True)
class Target:
    """A reproduction target: what it makes and how.

    Attributes:
        name: CLI name (``probecommit reproduce NAME``).
        makes: The paper's tables and figures it regenerates.
        needs: Targets whose run directories it reads (run first).
        run: ``run(root, quick, progress, workers) -> results folder``.
    """

    name: str
    makes: tuple[str, ...]
    needs: tuple[str, ...]
    run: Callable[[Path, bool, Progress, int], Path]


#: The registered targets, in registration order (``reproduce all`` runs them in this order,
#: dependencies first), and paper item -> target (the paper's own numbering and its labels:
#: LaTeX numbers tables and figures in source order, Table I setup, II breadth, III audit, IV
#: insertion by split, V Test C, VI engines, VII hardware, VIII faults; Fig. 1 overview, 2
#: pipeline, 3 testbeds, 4 the failure the audit found, 5 hardware, 6 commit decision, 7 fault
#: signatures). Filled only through :func:`register`.
TARGETS: dict[str, Target] = {}
ALIASES: dict[str, str] = {}


def register(target: Target, aliases: tuple[str, ...] = ()) -> Target:
    """Register a reproduction target and the paper items it makes (each name and alias once)."""
    taken = [name for name in (target.name, *aliases) if name in TARGETS or name in ALIASES]
    if taken:
        raise ValueError(f"reproduce target or paper item {taken[0]!r} is registered twice")
    missing = [need for need in target.needs if need not in TARGETS]
    if missing:
        raise ValueError(f"target {target.name!r} needs {missing[0]!r}, which is not registered before it")
    TARGETS[target.name] = target
    ALIASES.update(dict.fromkeys(aliases, target.name))
    return target


# ----------------------------------------------------------------------------- tables


def markdown_to_latex(markdown: str) -> str:
    """A Markdown pipe table as a LaTeX ``tabular`` (booktabs), for pasting into a paper."""
    rows = [line.strip().strip("|").split("|") for line in markdown.strip().splitlines() if line.strip().startswith("|")]
    rows = [[cell.strip() for cell in row] for row in rows if not all(set(c.strip()) <= set("-: ") for c in row)]
    if not rows:
        return ""

    def esc(cell: str) -> str:
        for a, b in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("_", r"\_"), ("#", r"\#"),
                     ("$", r"\$"), ("~", r"\textasciitilde{}"), ("^", r"\textasciicircum{}")):
            cell = cell.replace(a, b)
        return cell.replace("`", "")

    head, body = rows[0], rows[1:]
    lines = [r"\begin{tabular}{@{}l" + "c" * (len(head) - 1) + "@{}}", r"\toprule", " & ".join(map(esc, head)) + r" \\",
             r"\midrule"]
    lines += [" & ".join(map(esc, row)) + r" \\" for row in body]
    lines += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines) + "\n"


def write_table(folder: Path, key: str, markdown: str) -> None:
    """``<key>.md`` and ``<key>.tex`` from a Markdown table."""
    write_text(folder / f"{key}.md", markdown if markdown.endswith("\n") else markdown + "\n")
    write_text(folder / f"{key}.tex", markdown_to_latex(markdown))


# ----------------------------------------------------------------------------- targets


def _insertion(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.report.insertion_study import reproduce_insertion

    folder = root / "insertion"
    rep = reproduce_insertion(folder, quick=quick, progress=progress, workers=workers)
    results = folder / "results"
    for name in list(rep.tables):
        md = results / f"{name}.md"
        if md.is_file():
            write_text(results / f"{name}.tex", markdown_to_latex(md.read_text()))
    return results


#: Options a target may read (``reproduce(..., options={...})``): breadth's family subset.
OPTIONS: dict[str, Any] = {}


def insertion_row(root: Path) -> dict[str, Any] | None:
    """Table II's insertion row (failure on Split A, cover k = 5) from this reproduction's insertion
    results, or None when ``reproduce insertion`` has not run under ``root``."""
    path = root / "insertion" / "results" / "results.json"
    if not path.is_file():
        return None
    t = json.loads(path.read_text())["results"]["table_insertion"]
    nan = [float("nan")] * 3
    bb, pr, paired = t["A.no_probe"], t["A.cover_k5"], t.get("A.paired_reduction_k5", nan)
    return {"family": "insertion_A", "k": 5, "blind_bayes": bb[0], "blind_bayes_lo": bb[1], "blind_bayes_hi": bb[2],
            "blind_robust": float("nan"), "blind_robust_lo": float("nan"), "blind_robust_hi": float("nan"),
            "probe_robust": pr[0], "probe_robust_lo": pr[1], "probe_robust_hi": pr[2],
            "paired": paired[0], "paired_lo": paired[1], "paired_hi": paired[2],
            "paired_robust": float("nan"), "paired_robust_lo": float("nan"), "paired_robust_hi": float("nan")}


def _breadth(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    import pandas as pd

    from probecommit.audit.stats import DEFAULT_RESAMPLES
    from probecommit.studies.breadth import (BREADTH_FAMILIES, FAMILY_K, SIGN_FLIP_ROWS, SUCCESS_FAMILIES,
                                             breadth_markdown, budget_curves, paper_config, plot_budget_curves,
                                             quick_config, run_breadth, sign_flip_summary, truth_rows)

    families = tuple(OPTIONS.get("families") or BREADTH_FAMILIES)
    unknown = [f for f in families if f not in BREADTH_FAMILIES]
    if unknown:
        raise UsageError(f"unknown breadth famil{'y' if len(unknown) == 1 else 'ies'} {', '.join(unknown)}; "
                         f"available: {', '.join(BREADTH_FAMILIES)}")
    folder = root / "breadth"
    results = folder / "results"
    results.mkdir(parents=True, exist_ok=True)
    progress("breadth: families", 0, len(families))
    table = run_breadth(families, folder / "runs", quick=quick, workers=workers)
    runs = {f: folder / "runs" / next(p.name for p in (folder / "runs").iterdir()
                                      if p.name == f or p.name == f"{f}-quick") for f in families}
    # The curves read the episodes Table II reads (grasp: its feasible truths), the ones stored for verify.
    episodes_of = breadth_episodes(families, runs, quick)
    curves = budget_curves(episodes_of)
    progress("breadth: families", len(families), len(families))
    sign_flips = {}
    store_breadth_episodes(episodes_of, results / "breadth_episodes.parquet")
    flip_rows = []
    for family in (f for f in families if f in SUCCESS_FAMILIES):
        config = paper_config(family)
        config = quick_config(config) if quick else config
        rows = truth_rows(config, runs[family])  # stored: verify recomputes the sign count from them
        sign_flips[family] = sign_flip_summary(rows, FAMILY_K[family])
        flip_rows.append(rows.assign(family=family))
    if flip_rows:
        table_rows = pd.concat(flip_rows, ignore_index=True)
        write_with(results / SIGN_FLIP_ROWS, lambda f: table_rows.to_parquet(f, compression="zstd", index=False))
    row = insertion_row(root)
    if row is not None:
        table = pd.concat([pd.DataFrame([row]), table], ignore_index=True)
    write_with(results / "table_II_breadth.parquet", table.to_parquet)
    write_with(results / "budget_curves.parquet", curves.to_parquet)
    write_table(results, "table_II_breadth", breadth_markdown(table))
    plot_budget_curves(curves, results / "fig_breadth_budget.png")
    rows = json.loads(table.to_json(orient="records"))
    payload = {"results": {"settings": {"k": 5, "resamples": DEFAULT_RESAMPLES, "seed": 0},
                           "table_II": {row["family"]: row for row in rows},
                           "curves": json.loads(curves.to_json(orient="records")),
                           "sign_flip_over_truths": sign_flips}}
    write_text(results / "results.json", json.dumps(payload, indent=1))
    return results


def breadth_episodes(families: tuple[str, ...], runs: dict[str, Path], quick: bool) -> dict[str, Any]:
    """Every family's episodes as Table II reads them (grasp: its feasible truths)."""
    from probecommit.studies.breadth import (SUCCESS_FAMILIES, feasible_episodes, paper_config, quick_config,
                                             read_episodes)

    out = {}
    for family in families:
        episodes = read_episodes(runs[family])
        if family in SUCCESS_FAMILIES:
            config = paper_config(family)
            episodes = feasible_episodes(quick_config(config) if quick else config, runs[family], episodes)
        out[family] = episodes
    return out


def store_breadth_episodes(episodes_of: dict[str, Any], path: Path) -> None:
    """The episodes of :func:`breadth_episodes` in one compact file: verify recomputes Table II and
    the budget curves from it."""
    import pandas as pd

    table = pd.concat([e.assign(family=f) for f, e in episodes_of.items()], ignore_index=True)
    write_with(path, lambda buf: table.to_parquet(buf, compression="zstd", index=False))


def _beyond(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.studies.beyond import reproduce_beyond

    results = root / "beyond" / "results"
    push1d = next((root / "breadth" / "runs").glob("push1d*"), None)
    reproduce_beyond(root / "insertion" / "runs", results, push1d_run=push1d, workers=workers,
                     progress=lambda step, d, t: progress(f"beyond: {step}", d, t))
    return results


register(Target("insertion", ("Table III (tab:audit)", "Table IV (tab:insertion)", "Table V (tab:testc)",
                              "Table VIII (tab:faults)", "Fig. 4 (fig:teaser)", "Fig. 6 (fig:decision)",
                              "Fig. 7 (fig:signatures)", "scan and cover search", "re-splits, robust filters"),
                (), _insertion),
         ("table-3", "table-4", "table-5", "table-8", "fig-4", "fig-6", "fig-7", "tab:audit", "tab:insertion",
          "tab:testc", "tab:faults", "fig:teaser", "fig:decision", "fig:signatures"))
register(Target("breadth", ("Table II (tab:breadth: insertion A, 1-D push, 2-D push MuJoCo and PyBullet, darts, "
                            "hinge, shuffleboard, grasp)", "miss-vs-budget figure", "grasp's sign-flip over truths"),
                (), _breadth),
         ("table-2", "tab:breadth"))
register(Target("beyond", ("hull set at t = 1", "resample-move belief", "adaptive probes"), ("insertion", "breadth"),
                _beyond))


def resolve(names: list[str]) -> list[str]:
    """Targets to run, dependencies first; ``all`` is every target.

    Raises:
        ValueError: an unknown name (lists the targets and aliases).
    """
    wanted: list[str] = []
    for name in names:
        if name == "all":
            wanted += list(TARGETS)
        elif name in TARGETS:
            wanted.append(name)
        elif name in ALIASES:
            wanted.append(ALIASES[name])
        else:
            raise UsageError(f"unknown reproduce target {name!r}; targets: {', '.join(TARGETS)}, all; "
                             f"paper items: {', '.join(sorted(ALIASES))}")
    order: list[str] = []

    def add(name: str) -> None:
        for need in TARGETS[name].needs:
            add(need)
        if name not in order:
            order.append(name)

    for name in wanted:
        add(name)
    return order


def listing() -> list[tuple[str, str, str]]:
    """``(target, what it makes, needs)`` rows for ``reproduce --list``."""
    rows = [(t.name, ", ".join(t.makes), ", ".join(t.needs) or "-") for t in TARGETS.values()]
    rows += [(alias, f"= {target}", "-") for alias, target in sorted(ALIASES.items())]
    return rows


def engine_calls_under(folder: str | Path) -> dict[str, int]:
    """Engine queries recorded in the manifests of every run directory under ``folder``, per engine."""
    totals: dict[str, int] = {}
    for manifest in sorted(Path(folder).rglob("manifest.json")):
        try:
            data = json.loads(manifest.read_text())
        except (OSError, ValueError):
            continue
        calls = data.get("engine_calls") or {}
        engine = str(data.get("engine", "?"))
        totals[engine] = totals.get(engine, 0) + int(sum(int(v) for v in calls.values()))
    return totals


def machine() -> dict[str, Any]:
    """The machine a reproduction runs on (REPRODUCTION.md describes it from this record)."""
    import os
    import platform

    cpu, vector = platform.processor() or platform.machine(), "?"
    try:
        info = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        info = []
    for line in info:
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
        if line.startswith("flags") and vector == "?":
            vector = _widest_vector_unit(set(line.split(":", 1)[1].split()))
    return {"cpu": cpu, "vector": vector, "cores": os.cpu_count() or 0, "platform": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__}


def _widest_vector_unit(flags: set[str]) -> str:
    """The widest x86 vector extension the CPU reports: NumPy's and torch's kernels are chosen by it, which is why
    two CPUs of one model name can still give different low digits (and the GRU's training amplifies them)."""
    for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX"), ("sse4_2", "SSE4.2")):
        if flag in flags:
            return name
    return "?"


#: Targets that read another target's results when that has run under the same root, without
#: needing it: breadth puts the insertion study's Split A row into Table II (``insertion_row``).
#: Side by side, such a target is made again once what it reads is done (``report.schedule``).
READS_IF_RUN: dict[str, tuple[str, ...]] = {"breadth": ("insertion",)}


def side_by_side_lanes(workers: int, targets: int) -> int:
    """Targets run at once for ``--workers``: up to ``workers`` (at most the CPUs and the targets), 1 for one worker."""
    import os

    return max(1, min(int(workers), os.cpu_count() or 1, int(targets)))


def reproduce(names: list[str], root: str | Path, quick: bool = False, progress: Progress = _noop,
              workers: int = 1, options: dict[str, Any] | None = None) -> dict[str, Any]:
    """Run the named targets (dependencies first) into ``root``.

    ``options``: target options, e.g. ``{"families": ["push1d", "darts"]}`` for breadth.
    With ``workers`` >= 2 (and as many CPUs), independent targets run side by side in
    processes of their own (``report.schedule``), each given ``workers // lanes`` workers;
    the numbers are the same as one after the other.

    Returns:
        ``{"targets": {name: results folder}, "wall_s": {name: seconds},
        "engine_calls": {name: {engine: queries}}}`` (queries recorded in the run manifests).
    """
    root = Path(root)
    OPTIONS.clear()
    OPTIONS.update(options or {})
    out: dict[str, Any] = {"targets": {}, "wall_s": {}, "engine_calls": {}, "machine": machine()}
    order = resolve(names)
    lanes = side_by_side_lanes(workers, len(order))
    if lanes > 1:  # independent targets in processes of their own, each with its share of the workers
        from probecommit.report.schedule import MARKERS, run_target, side_by_side

        inner = max(1, workers // lanes)
        results = side_by_side(order, {t: TARGETS[t].needs for t in order}, lanes,
                               lambda pool, name: pool.submit(run_target, name, str(root), quick, inner, dict(OPTIONS)),
                               progress, READS_IF_RUN, markers=root / MARKERS)
        out["side_by_side"] = lanes
        for name in order:
            out["targets"][name], out["wall_s"][name] = results[name]
            out["engine_calls"][name] = engine_calls_under(root / name)
        root.mkdir(parents=True, exist_ok=True)
        write_text(root / "reproduction.json", json.dumps(out, indent=1))
        return out
    with shared_engine_answers():  # one engine cache for every run and replay: no query twice
        for name in order:
            start = time.perf_counter()
            out["targets"][name] = str(TARGETS[name].run(root, quick, progress, workers))
            out["wall_s"][name] = time.perf_counter() - start
            out["engine_calls"][name] = engine_calls_under(root / name)
    root.mkdir(parents=True, exist_ok=True)
    write_text(root / "reproduction.json", json.dumps(out, indent=1))
    return out


# ----------------------------------------------------------------------------- publish

#: Files small enough to version (episode tables are stored compactly: verify recomputes from them).
PUBLISHED_SUFFIXES = (".md", ".tex", ".json", ".png", ".pdf", ".parquet")


def publish(results: dict[str, str | Path], repo_root: str | Path) -> Path:
    """Copy each target's results into ``results/paper/<target>/`` with a hash manifest."""
    from probecommit.report.manifest import write_manifest

    target_root = Path(repo_root) / "results" / "paper"
    for name, folder in results.items():
        dest = target_root / name
        dest.mkdir(parents=True, exist_ok=True)
        fresh = {p.name for p in Path(folder).iterdir() if p.is_file()}
        for stale in sorted(dest.iterdir()):  # a renamed or dropped file must not linger in the publication
            if stale.is_file() and stale.suffix in PUBLISHED_SUFFIXES and stale.name not in fresh:
                stale.unlink()
        for path in sorted(Path(folder).iterdir()):
            if path.is_file() and path.suffix in PUBLISHED_SUFFIXES:
                shutil.copy2(path, dest / path.name)
        write_manifest(dest)
    return target_root


def engines_markdown(table: Any) -> str:
    """Table VI: ours per engine and variant, the paper's row under each of ours (labelled)."""
    from probecommit.studies.paper_values import PRINTED as PAPER

    columns = [tuple(c.split("/", 1)) if isinstance(c, str) else tuple(c) for c in table.columns]  # flat when re-rendered
    header = "| quantity | " + " | ".join(f"{e} {v}" for e, v in columns) + " |"
    lines = [header, "|---" * (len(columns) + 1) + "|"]
    for label, values in table.iterrows():
        metric = label.replace(" ", "_")
        lines.append(f"| {label} (ours) | " + " | ".join(f"{v:.3f}" for v in values) + " |")
        lines.append(f"| {label} (paper) | " + " | ".join(PAPER.get(f"tab:engines.{e}/{v}.{metric}", "--")
                                                      for e, v in columns) + " |")
    return "\n".join(lines)


def engine_scans_markdown(scans: dict[str, Any]) -> str:
    """Each engine's scanned boundary offset and capture window, beside the paper's (Sec. V-C)."""
    from probecommit.studies.paper_values import PRINTED as PAPER

    lines = ["| engine | boundary offset (mm, hg + delta) | SD | capture window / w(c) | SD over truths | paper offset | "
             "paper ratio |", "|---|---|---|---|---|---|---|"]
    for engine, s in scans.items():
        b, c = s["boundary"], s["capture"]
        offset = PAPER.get(f"T18-engine-scans.{engine}_offset", "--")
        ratio = PAPER.get(f"T18-engine-scans.{engine}_ratio", "--")
        if f"T18-engine-scans.{engine}_ratio_sd" in PAPER:
            ratio += f" (SD {PAPER[f'T18-engine-scans.{engine}_ratio_sd']})"
        lines.append(f"| {engine} | {b['delta']:+.3f} | {b['sd']:.3f} | {c['ratio_mean']:.3f} | {c['ratio_sd']:.3f} | "
                     f"{offset} | {ratio} |")
    return "\n".join(lines)


def _engines(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.studies.engines import run_engine_study
    from probecommit.studies.protocol import load_protocol

    protocol = load_protocol()
    if quick:
        protocol = protocol.quick_version()
    folder = root / "engines"
    results = folder / "results"
    results.mkdir(parents=True, exist_ok=True)
    study = run_engine_study(protocol, folder / "runs", workers=workers, progress=progress)
    table, escape = study["table"], study["escape"]
    write_table(results, "table_VI_engines", engines_markdown(table))
    write_table(results, "engine_scans", engine_scans_markdown(study["scans"]))
    flat = table.copy()
    flat.columns = [f"{e}/{v}" for e, v in flat.columns]
    write_with(results / "table_VI_engines.parquet", flat.to_parquet)
    write_with(results / "escape_by_budget.parquet", escape.to_parquet)
    write_with(results / "engine_episodes.parquet",
               lambda buf: study["episodes"].to_parquet(buf, compression="zstd", index=False))
    write_with(results / "engine_scans.parquet",
               lambda buf: study["scan_rows"].to_parquet(buf, compression="zstd", index=False))
    payload = {"results": {
        "settings": study["bootstrap"],
        "table": {f"{e}/{v}": dict(zip([r.replace(" ", "_") for r in table.index], map(float, table[(e, v)])))
                  for e, v in table.columns},
        "paired_failure": study["paired"], "scans": study["scans"],
        "escape_by_budget": json.loads(escape.to_json(orient="records")),
        # The same numbers by name, so a claim can cite one (``paired.pybullet/mj_offset``, ``escape.sapien/deployed.8``).
        "paired": {f"{p['engine']}/{p['variant']}": p["failure_difference"] for p in study["paired"]},
        "escape": {f"{e}/{v}": {str(int(r["k"])): float(r["escape"]) for _, r in part.iterrows()}
                   for (e, v), part in escape.groupby(["engine", "variant"], sort=False)},
    }}
    write_text(results / "results.json", json.dumps(payload, indent=1, default=float))
    return results


register(Target("engines", ("Table VI (tab:engines: PyBullet and PhysX)",
                            "scanned boundary offsets and capture windows per engine", "escape against k per engine"),
                (), _engines),
         ("table-6", "tab:engines"))


def _gru(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.studies.gru import reproduce_gru

    runs = root / "breadth" / "runs"
    pipeline = runs / ("push2d-quick" if quick and (runs / "push2d-quick").is_dir() else "push2d")
    results = root / "gru" / "results"
    reproduce_gru(results, pipeline, quick=quick, progress=progress, workers=workers)
    return results


register(Target("gru", ("the GRU baseline on MuJoCo 2-D pushing, with the pre-registered equivalence test",),
                ("breadth",), _gru))


def _robot(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.report.figures import save_figure
    from probecommit.report.robot_figures import aim_error_caption, aim_error_figure, fault_sweep_figure, sweep_caption
    from probecommit.studies.robot import (RIG_LABEL, SIM_ERROR_AT_RIG_SCALE_MM, run_robot_study, sweep_markdown,
                                           table_markdown)
    from probecommit.tasks.rig.model import rig_half_gap, rig_window

    results = root / "robot" / "results"
    results.mkdir(parents=True, exist_ok=True)
    study = run_robot_study(root / "robot" / "runs", quick=quick, progress=progress)
    write_with(results / "robot_episodes.parquet", study.episodes.rows.to_parquet)
    write_with(results / "table_robot.parquet", study.table.to_parquet)
    write_with(results / "fault_boundary.parquet", study.boundary.to_parquet)
    write_with(results / "fault_prior.parquet", study.prior.to_parquet)
    write_with(results / "fault_sweep_episodes.parquet",
               lambda buf: study.sweep_episodes.to_parquet(buf, compression="zstd", index=False))
    write_table(results, "table_VII_hardware_simulated_rig", table_markdown(study.table))
    write_table(results, "fault_boundary_simulated_rig", sweep_markdown(study.boundary, "boundary pulled in (mm)"))
    write_table(results, "fault_prior_simulated_rig", sweep_markdown(study.prior, "prior half-width (mm)"))
    save_figure(aim_error_figure(study.episodes.rows, float(rig_window(1.0)), float(rig_half_gap(1.0)), title=RIG_LABEL),
                results / "fig_5b_hardware_simulated_rig_aim_error.png", caption=aim_error_caption(study.episodes.rows))
    save_figure(fault_sweep_figure(study.boundary, "boundary pulled inward (mm)", SIM_ERROR_AT_RIG_SCALE_MM,
                                   "sim. error at rig scale", title=RIG_LABEL),
                results / "fig_5c_hardware_simulated_rig_boundary_fault.png",
                caption=sweep_caption(study.boundary, "a tap boundary pulled inward"))
    save_figure(fault_sweep_figure(study.prior.sort_values("size"), "prior half-width (mm)", title=RIG_LABEL),
                results / "fig_5d_hardware_simulated_rig_prior_fault.png",
                caption=sweep_caption(study.prior, "a narrowed prior"))
    write_text(results / "results.json", json.dumps(study.payload(), indent=1, default=float))
    return results


register(Target("robot", ("Table VII (tab:hardware) on the simulated rig, run as a robot session",
                          "Fig. 5b-d (fig:hardware) on the simulated rig: aim error against taps, replays under boundary "
                          "and prior faults"), (), _robot),
         ("table-7", "tab:hardware", "fig-5", "fig:hardware"))


#: Table I's row order (the paper's), then the transfer and the rig.
SETUP_ORDER = ("insertion", "push1d", "push2d", "darts", "hinge", "shuffleboard", "grasp", "rig")
#: The paper's Table I engines and n, for the side-by-side.
#: The paper's Table I engines (text); its n come from the paper-values table.
PAPER_TABLE_I_ENGINES = {"insertion": "all three", "push1d": "analytic", "push2d": "MuJoCo", "darts": "MuJoCo",
                         "hinge": "MuJoCo", "shuffleboard": "SAPIEN", "grasp": "MuJoCo"}


def paper_setup_cell(family: str) -> str:
    """``engine, n`` of Table I for ``family`` (``--`` for a family the paper does not have)."""
    from probecommit.studies.paper_values import PRINTED

    n = PRINTED.get(f"tab:setup.{family}.n")
    if n is None:
        return "--, --"
    times = "{\\times}"
    return f"{PAPER_TABLE_I_ENGINES[family]}, {n.replace(times, ' x ')}"


def table_I() -> tuple[list[str], list[dict[str, Any]]]:
    """Table I's Markdown lines and records, from the task registry (verify renders it again)."""
    from probecommit.tasks.registry import families

    specs = families()
    lines = ["| family | engines (ours) | latents | probe / action | sigma | budgets k | n; metric | paper: engine, n |",
             "|---|---|---|---|---|---|---|---|"]
    rows = []
    for name in SETUP_ORDER:
        spec = specs[name]
        s = spec.summary
        engines = ", ".join(e for e in spec.engines if e != "analytic") or "analytic"
        lines.append(f"| {name} | {engines} | {s.get('latents', '')} | {s.get('probe', '')} / {s.get('action', '')} | "
                     f"{s.get('sigma', '')} | {s.get('budgets', '')} | {s.get('n', '')}; {s.get('metric', '')} | "
                     f"{paper_setup_cell(name)} |")
        rows.append({"family": name, "engines": list(spec.engines), **s})
    return lines, rows


def _setup(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    """Table I from the task registry, and Fig. 1b (an insertion belief after taps 1, 3, 5)."""
    from importlib import resources

    from probecommit.report.demo import belief_figure
    from probecommit.runner.config import parse_config
    from probecommit.runner.study import run_study
    from probecommit.store.yamlsafe import load_yaml

    results = root / "setup" / "results"
    results.mkdir(parents=True, exist_ok=True)
    lines, rows = table_I()
    write_table(results, "table_I_setup", "\n".join(lines))
    data = load_yaml(resources.files("probecommit").joinpath("configs/demo.yaml").read_text(), "configs/demo.yaml")
    if quick:
        data["instances"]["count"] = 2
    run = run_study(parse_config(data), root / "setup" / "runs" / ("demo-quick" if quick else "demo"), workers=workers)
    figure = belief_figure(run.run_dir, results, series=results / "fig_1b_data.parquet")
    figure.rename(results / "fig_1b_overview_belief.png")
    pdf = figure.with_suffix(".pdf")
    if pdf.is_file():
        pdf.rename(results / "fig_1b_overview_belief.pdf")
    write_text(results / "results.json", json.dumps(
        {"results": {"families": rows, "families_by_name": {row["family"]: row for row in rows}}}, indent=1))
    return results


register(Target("setup", ("Table I (tab:setup: the task families, from the registry)",
                          "Fig. 1b (fig:overview: an insertion belief after taps 1, 3 and 5)"), (), _setup),
         ("table-1", "tab:setup"))  # Fig. 1 is the figures target's, which runs setup first


def plot_pricing(table: Any, path: str | Path) -> Path:
    """``J_lambda(k)`` against the price for each family (one small panel each)."""
    import matplotlib.pyplot as plt

    from probecommit.report.figures import save_figure

    n = len(table)
    fig, axes = plt.subplots(1, max(n, 1), figsize=(7.16, 2.0), squeeze=False)
    for ax, (_, r) in zip(axes[0], table.iterrows()):
        top = max(r["blind_above"] * 1.6, 1e-4)
        lam = np.linspace(0, top, 200)
        for k, m, style in ((0, r["miss_0"], "k-"), (2, r["miss_2"], "C0--"), (5, r["miss_5"], "C3-.")):
            ax.plot(lam, m + k * lam, style, lw=1.0, label=f"k = {k}")
        for price in {r["blind_above"], r["five_below"]}:
            ax.axvline(price, color="0.6", lw=0.6, ls=":")
        family = str(r["family"])
        ax.set_title(family.replace("_pybullet", " (PyBullet)").replace("_", " "))
    axes[0][0].set_ylabel("J(k) = miss + λk")
    fig.supxlabel("price λ per probe (loss units)", fontsize=8)  # one label: six would collide at this width
    fig.tight_layout(rect=(0, 0, 1, 0.86))
    fig.legend(*axes[0][0].get_legend_handles_labels(), loc="lower center", bbox_to_anchor=(0.5, 0.86), ncol=3,
               frameon=False)  # above the panels, off the data
    return save_figure(fig, path, caption="Probe pricing: J(k) = miss(k) + λk against the price λ per probe, per family, "
                                          "for k = 0, 2 and 5 probes; dotted: the break-even prices (in the loss's units per probe).")


def _cost(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    import pandas as pd

    from probecommit.studies.breadth import SUCCESS_FAMILIES
    from probecommit.studies.pricing import pricing_markdown, pricing_table

    curves = pd.read_parquet(root / "breadth" / "results" / "budget_curves.parquet")
    # Prices are in the loss's units per probe: the miss families (grasp's loss is a success rate).
    curves = curves[~curves["family"].isin(SUCCESS_FAMILIES)]
    results = root / "cost" / "results"
    results.mkdir(parents=True, exist_ok=True)
    table = pricing_table(curves)
    write_with(results / "pricing.parquet", table.to_parquet)
    write_table(results, "table_pricing", pricing_markdown(table))
    plot_pricing(table, results / "fig_pricing.png")
    records = json.loads(table.to_json(orient="records"))
    write_text(results / "results.json", json.dumps(
        {"results": {"pricing": records, "prices": {r["family"]: r for r in records}}}, indent=1))
    return results


register(Target("cost", ("probe pricing J(k) = miss(k) + lambda k: break-even prices per family, figure",),
                ("breadth",), _cost))


def _fig1_spec(run_dir: Path) -> dict[str, Any]:
    """Fig. 1's episode (the one Fig. 1b draws): its first five taps, whether each read the pocket, the hole and the aim."""
    from probecommit.report.demo import FIGURE_BUDGETS, illustrative_episode
    from probecommit.runner.replay import load_run, trace_for_run

    loaded = load_run(run_dir)
    trace, model, _ = trace_for_run(loaded)
    row = illustrative_episode(trace, loaded.episodes)
    batch, k = trace.batch, max(FIGURE_BUDGETS)
    ep = loaded.episodes
    hit = ep[(ep.instance_id == batch.instance_id[row]) & (ep.repeat == batch.repeat[row]) & (ep.k == k)
             & (ep.method == "probe_robust")]
    truth = batch.truths[row]
    return {"taps": [[float(u), bool(y < -7.5)] for u, y in zip(batch.u[row, :k, 0], batch.y[row, :k, 0])],
            "x_hole": float(model.decision(truth)), "c": float(truth[1]), "aim": float(hit["action"].iloc[0])}


def _figures(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    """Fig. 1a/1c (the demo episode's taps and insertion, rendered), Fig. 2 (the pipeline), Fig. 3 (every scene)."""
    from probecommit.report.pipeline_diagram import pipeline_figure
    from probecommit.report.scene_figures import fig1_panel, fig3_scenes
    from probecommit.report.scenes import render_scenes

    results = root / "figures" / "results"
    results.mkdir(parents=True, exist_ok=True)
    renders = root / "figures" / "renders"  # raw renders stay out of the published folder
    runs = root / "setup" / "runs"
    demo = runs / ("demo-quick" if quick else "demo")
    spec = _fig1_spec(demo) if demo.is_dir() else None
    listing = render_scenes(renders, spec)
    pipeline_figure(results / "fig_2_pipeline.png")
    fig3_scenes(renders, results / "fig_3_testbeds.png")
    if spec is not None:
        fig1_panel(renders, "a", spec, results / "fig_1a_overview_taps.png")
        fig1_panel(renders, "c", spec, results / "fig_1c_overview_insertion.png")
    write_text(results / "results.json", json.dumps({"results": {"scenes": listing, "fig1": spec}}, indent=1))
    return results


register(Target("figures", ("Fig. 1a and 1c (fig:overview: the demo episode's taps and insertion, rendered)",
                            "Fig. 2 (fig:pipeline, drawn by code)", "Fig. 3 (fig:testbeds: the scene of every family)"),
                ("setup",), _figures),
         ("fig-2", "fig:pipeline", "fig-3", "fig:testbeds", "fig-1", "fig:overview"))  # Fig. 1b: setup, run first
def _explain(root: Path, quick: bool, progress: Progress, workers: int) -> Path:
    from probecommit.studies.explain import reproduce_explain

    return reproduce_explain(root, quick=quick, progress=progress, workers=workers, ready=OPTIONS.get("_ready"))


register(Target("explain", ("the measurements behind each difference from the paper, and the paper's items "
                            "computed from stored runs (EXPLAIN_KEYS.md)",),
                ("insertion", "engines", "gru"), _explain))
