"""Render every published text file again from the stored data, for ``verify`` to compare.

Why: a table cell, a rounding, a row order, a prose number or a paper value edited in a
published file (and the manifest re-hashed) is caught only by deriving the text again: each
study's tables come from its ``results.json`` and Parquet tables through the same functions
that wrote them; each ``.tex`` from its ``.md``; REPRODUCTION.md and report.html from the
whole publication (``report.publish.write_reproduction_md`` run on a copy), with claims.json
and the published-numbers ledger it writes beside them.

``RENDERERS[study][file](folder, results) -> text``. A published text file with no renderer is
reported as traced only (its bytes hashed, its numbers not derived).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable

import pandas as pd

Renderer = Callable[[Path, dict[str, Any]], str]


def _insertion() -> dict[str, Renderer]:
    from probecommit.report.insertion_tables import RENDERERS as TABLES

    return {f"{name}.md": (lambda fn: lambda folder, r: fn(r, folder))(fn) for name, fn in TABLES.items()}


def _breadth() -> dict[str, Renderer]:
    from probecommit.studies.breadth import breadth_markdown

    return {"table_II_breadth.md": lambda folder, r: breadth_markdown(pd.read_parquet(folder / "table_II_breadth.parquet"))}


def _cost() -> dict[str, Renderer]:
    from probecommit.studies.pricing import pricing_markdown

    return {"table_pricing.md": lambda folder, r: pricing_markdown(pd.read_parquet(folder / "pricing.parquet"))}


def _robot() -> dict[str, Renderer]:
    from probecommit.studies.robot import sweep_markdown, table_markdown

    return {"table_VII_hardware_simulated_rig.md": lambda folder, r: table_markdown(
                pd.read_parquet(folder / "table_robot.parquet")),
            "fault_boundary_simulated_rig.md": lambda folder, r: sweep_markdown(
                pd.read_parquet(folder / "fault_boundary.parquet"), "boundary pulled in (mm)"),
            "fault_prior_simulated_rig.md": lambda folder, r: sweep_markdown(
                pd.read_parquet(folder / "fault_prior.parquet"), "prior half-width (mm)")}


def _engines() -> dict[str, Renderer]:
    from probecommit.report.paper import engine_scans_markdown, engines_markdown

    return {"table_VI_engines.md": lambda folder, r: engines_markdown(pd.read_parquet(folder / "table_VI_engines.parquet"))
            + "\n",
            "engine_scans.md": lambda folder, r: engine_scans_markdown(r["scans"]) + "\n"}


def _gru() -> dict[str, Renderer]:
    from probecommit.studies.gru import gru_markdown

    return {"table_gru.md": lambda folder, r: gru_markdown(r)}


def _setup() -> dict[str, Renderer]:
    from probecommit.report.paper import table_I

    return {"table_I_setup.md": lambda folder, r: "\n".join(table_I()[0]) + "\n"}


def _explain() -> dict[str, Renderer]:
    from probecommit.studies.explain.study import summary_markdown

    return {"explain.md": lambda folder, r: summary_markdown(r)}


RENDERERS: dict[str, Callable[[], dict[str, Renderer]]] = {
    "insertion": _insertion, "breadth": _breadth, "cost": _cost, "robot": _robot, "engines": _engines, "gru": _gru,
    "setup": _setup, "explain": _explain}


def expected_texts(study: str) -> list[str]:
    """The tables a study always publishes (its renderers' files)."""
    return sorted(RENDERERS[study]()) if study in RENDERERS else []


def study_texts(folder: Path) -> dict[str, str]:
    """Every text file of a study folder rendered again: its tables and each table's ``.tex``."""
    from probecommit.report.paper import markdown_to_latex

    results = json.loads((folder / "results.json").read_text()).get("results", {})
    out: dict[str, str] = {}
    for name, render in RENDERERS.get(folder.name, lambda: {})().items():
        if (folder / name).is_file():
            out[name] = render(folder, results)
            tex = Path(name).with_suffix(".tex").name
            if (folder / tex).is_file():
                out[tex] = markdown_to_latex(out[name])
    return out


def publication_texts(root: Path) -> dict[str, bytes]:
    """The publication-level files rendered again from a copy of the publication ``root``.

    ``report.publish.write_reproduction_md`` runs on the copy as publishing ran it: claims.json
    (the claims' statuses, recomputed from the registry and every study's results), REPRODUCTION.md,
    the published-numbers ledger and report.html. Keys are paths relative to ``root``.
    """
    from probecommit.report.claims_json import CLAIMS_NAME
    from probecommit.report.ledger import LEDGER_NAME
    from probecommit.report.publish import write_reproduction_md

    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "results" / "paper"
        shutil.copytree(root, copy, ignore=shutil.ignore_patterns("report.html", "MANIFEST.json", CLAIMS_NAME))
        md = write_reproduction_md(Path(tmp))
        return {CLAIMS_NAME: (copy / CLAIMS_NAME).read_bytes(), "../../REPRODUCTION.md": md.read_bytes(),
                LEDGER_NAME: (copy / LEDGER_NAME).read_bytes(), "report.html": (copy / "report.html").read_bytes()}


def first_difference(published: str, expected: str) -> str:
    """Where two texts first differ: line number and the two lines (the number a reader sees)."""
    a, b = published.splitlines(), expected.splitlines()
    for i, (x, y) in enumerate(zip(a, b), start=1):
        if x != y:
            return f"line {i} reads {_excerpt(x, y)!r}, the stored data give {_excerpt(y, x)!r}"
    if len(a) != len(b):
        return f"{len(a)} lines where the stored data give {len(b)}"
    return "the bytes differ (line endings or trailing text)"


def _excerpt(line: str, other: str, width: int = 60) -> str:
    """The part of ``line`` around its first difference with ``other``."""
    at = next((i for i, (x, y) in enumerate(zip(line, other)) if x != y), min(len(line), len(other)))
    start = max(0, at - width // 2)
    return ("..." if start else "") + line[start:start + width] + ("..." if start + width < len(line) else "")


# ----------------------------------------------------------------------------- figures


def _robot_figures() -> dict[str, Callable[[Path, Path], Any]]:
    from probecommit.report.figures import save_figure
    from probecommit.report.robot_figures import aim_error_caption, aim_error_figure, fault_sweep_figure, sweep_caption
    from probecommit.studies.robot import RIG_LABEL, SIM_ERROR_AT_RIG_SCALE_MM
    from probecommit.tasks.rig.model import rig_half_gap, rig_window

    def aim(folder: Path, out: Path) -> Any:
        rows = pd.read_parquet(folder / "robot_episodes.parquet")
        return save_figure(aim_error_figure(rows, float(rig_window(1.0)), float(rig_half_gap(1.0)), title=RIG_LABEL), out,
                           caption=aim_error_caption(rows))

    def boundary(folder: Path, out: Path) -> Any:
        sweep = pd.read_parquet(folder / "fault_boundary.parquet")
        return save_figure(fault_sweep_figure(sweep, "boundary pulled inward (mm)", SIM_ERROR_AT_RIG_SCALE_MM,
                                              "sim. error at rig scale", title=RIG_LABEL), out,
                           caption=sweep_caption(sweep, "a tap boundary pulled inward"))

    def prior(folder: Path, out: Path) -> Any:
        sweep = pd.read_parquet(folder / "fault_prior.parquet")
        return save_figure(fault_sweep_figure(sweep.sort_values("size"), "prior half-width (mm)", title=RIG_LABEL), out,
                           caption=sweep_caption(sweep, "a narrowed prior"))

    return {"fig_5b_hardware_simulated_rig_aim_error": aim, "fig_5c_hardware_simulated_rig_boundary_fault": boundary,
            "fig_5d_hardware_simulated_rig_prior_fault": prior}


def _figure_recipes() -> dict[str, dict[str, Callable[[Path, Path], Any]]]:
    """Study -> figure stem -> ``draw(folder, out_png)``: the same call that drew the figure, on the stored data.

    Fig. 2 (the pipeline) is drawn from code alone. Fig. 6 (the commit decision) is drawn from the
    coverage table, the gate curves and the gates' summary, each recomputed from stored rows; Fig. 4a
    (the scan section) from the scans and the drawn instance's stored readings; Fig. 4b (the decisive
    tap) from both beliefs' stored particles; Fig. 1b from its stored series (each budget's particles,
    aims and the taps). Scene renders (Fig. 1a, 1c, 3) are bound to no stored data.
    """
    from probecommit.report.figures import draw_belief_snapshots
    from probecommit.report.paper import plot_pricing
    from probecommit.report.pipeline_diagram import pipeline_figure
    from probecommit.studies.insertion import signature_n
    from probecommit.report.study_figures import fault_signatures
    from probecommit.studies.breadth import plot_budget_curves

    def signatures(folder: Path, out: Path) -> Any:
        k = int(json.loads((folder / "results.json").read_text())["results"]["setup"]["k_random"])
        n = signature_n(pd.read_parquet(folder / "faults_episodes.parquet"), k)
        return fault_signatures(pd.read_parquet(folder / "fault_signatures.parquet"), out, n=n)

    def decision(folder: Path, out: Path) -> Any:
        # Panel (b) and (c) from the gate curves and summary verify recomputes from the stored commits.
        from types import SimpleNamespace

        from probecommit.report.study_figures import decision_figure

        summary = pd.DataFrame(json.loads((folder / "results.json").read_text())["results"]["gates"]["summary"])
        gates = SimpleNamespace(curves=pd.read_parquet(folder / "gates_curves.parquet"), summary=summary)
        return decision_figure(pd.read_parquet(folder / "coverage_vs_nominal.parquet"), gates, out)

    def scan_section(folder: Path, out: Path) -> Any:
        from probecommit.report.study_figures import scan_figure

        scans = pd.read_parquet(folder / "scan.parquet")
        return scan_figure(pd.read_parquet(folder / "scan_grid.parquet"), scans, str(scans["instance_id"].iloc[0]),
                           float(scans["offset"].mean()), out)

    def decisive_tap(folder: Path, out: Path) -> Any:
        from probecommit.report.study_figures import draw_decisive_tap
        from probecommit.studies.insertion import DECISIVE_TAP

        return draw_decisive_tap(pd.read_parquet(folder / DECISIVE_TAP), out)

    return {
        "insertion": {"fig_7_signatures": signatures, "fig_6_decision": decision,
                      "fig_4a_teaser_scan_section": scan_section, "fig_4b_teaser_decisive_tap": decisive_tap},
        "breadth": {"fig_breadth_budget": lambda folder, out: plot_budget_curves(
            pd.read_parquet(folder / "budget_curves.parquet"), out)},
        "cost": {"fig_pricing": lambda folder, out: plot_pricing(pd.read_parquet(folder / "pricing.parquet"), out)},
        "robot": _robot_figures(),
        "setup": {"fig_1b_overview_belief": lambda folder, out: draw_belief_snapshots(
            pd.read_parquet(folder / "fig_1b_data.parquet"), out)},
        "figures": {"fig_2_pipeline": lambda folder, out: pipeline_figure(out)},  # drawn from code alone
    }


def study_figures(folder: Path) -> dict[str, bytes]:
    """Each figure of the study that can be drawn from its stored data, drawn again: PNG (without the
    data-digest chunk publishing adds) and PDF bytes by file name."""
    from probecommit.report.manifest import strip_stamp

    recipes = _figure_recipes().get(folder.name, {})
    out: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for stem, draw in recipes.items():
            if not (folder / f"{stem}.png").is_file():
                continue
            draw(folder, Path(tmp) / f"{stem}.png")
            for suffix in (".png", ".pdf"):
                drawn = Path(tmp) / f"{stem}{suffix}"
                if drawn.is_file():
                    out[f"{stem}{suffix}"] = strip_stamp(drawn.read_bytes()) if suffix == ".png" else drawn.read_bytes()
    return out
