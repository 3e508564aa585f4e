"""Every paper figure, placed at its slot's width, has no text under 7 pt; scene renders show their scene.

Font sizes are measured from the figure objects (every visible Text artist after a layout
pass: titles, labels, tick labels, legends, annotations), scaled by placed width / drawn width.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from probecommit.report import style

COLUMN, DOUBLE = style.COLUMN, style.DOUBLE


@pytest.fixture
def captured(monkeypatch):
    """Figures handed to save_figure, in order (they are measured before being closed)."""
    import probecommit.report.figures as F

    real = F.save_figure
    figs = []

    def keep(fig, path, dpi=None, caption=None):
        sizes = style.placed_sizes(fig, min(fig.get_size_inches()[0], keep.width))
        figs.append({"fig_width": float(fig.get_size_inches()[0]), "sizes": sizes, "caption": caption,
                     "labels": [t for _, t in sizes]})
        return real(fig, path, dpi, caption)

    keep.width = COLUMN
    import probecommit.report.pipeline_diagram as PD
    import probecommit.report.scene_figures as SF
    import probecommit.report.study_figures as ST

    for module in (F, ST, PD, SF):
        monkeypatch.setattr(module, "save_figure", keep)
    return keep, figs


def _gates():
    curves = pd.DataFrame({"signal": ["raw"] * 3 + ["adjusted"] * 3 + ["posterior_variance"] * 3 + ["oracle"] * 3,
                           "commit_rate": [0.2, 0.6, 1.0] * 4, "failure": [0.3, 0.25, 0.4, 0.35, 0.3, 0.4, 0.3, 0.2, 0.4, 0, 0, 0.4]})
    summary = pd.DataFrame({"signal": ["raw", "adjusted", "posterior_variance", "oracle"],
                            "claimed": [0.05, 0.2, np.nan, np.nan], "realized": [0.24, 0.33, 0.24, 0.0]})
    return SimpleNamespace(curves=curves, summary=summary)


def _assert_readable(record, placed: float) -> None:
    assert record["fig_width"] <= placed + 1e-6, "drawn wider than its slot: its text shrinks when placed"
    small = [(round(s, 2), t) for s, t in record["sizes"] if s < style.MIN_FONT - 1e-6]
    assert not small, small
    assert not any("_" in t for t in record["labels"]), [t for t in record["labels"] if "_" in t]


def test_column_figures_are_readable_at_one_column(tmp_path, captured):
    from probecommit.report.study_figures import decision_figure, fault_signatures

    keep, figs = captured
    rows = [{"fault": f, "k": k, **{m: 0.1 for m in ("escape", "coverage", "optimism", "failure")},
             **{f"{m}_{e}": 0.1 for m in ("escape", "coverage", "optimism", "failure") for e in ("lo", "hi")}}
            for f in ("none", "noise", "boundary", "prior", "particles", "frame") for k in range(1, 9)]
    fault_signatures(pd.DataFrame(rows), tmp_path / "sig.png", n=384)
    coverage = pd.DataFrame({"nominal": [0.5, 0.8, 0.95], "cluster_coverage": [0.55, 0.74, 0.95]})
    decision_figure(coverage, _gates(), tmp_path / "decision.png")
    from probecommit.report.study_figures import decisive_tap_figure, scan_figure

    scans = pd.DataFrame({"instance_id": "d0", "c": 0.8, "side": ["left", "right"], "boundary": [5.4, 5.4]})
    off = np.arange(-7, 7.01, 0.25)
    grid = pd.DataFrame({"instance_id": "d0", "offset_from_hole": off, "reading": np.where(abs(off) < 5.4, -13.8, 1.2)})
    scan_figure(grid, scans, "d0", 0.905, tmp_path / "scan.png")
    z = np.linspace(0, 4, 50)
    decisive_tap_figure(z, np.ones(50) / 50, z + 1, np.ones(50) / 50, 4.3, 4.5, -13.8, "after tap 3", tmp_path / "tap.png")
    assert len(figs) == 4
    for record in figs:
        _assert_readable(record, COLUMN)
    assert "n = 384" in figs[0]["caption"] and "band" in figs[0]["caption"]


def test_gates_panel_c_has_a_y_label_and_the_papers_legend():
    from probecommit.report.audit_report import gates_figure

    fig = gates_figure(_gates())
    curves, bars = fig.axes
    assert bars.get_ylabel()
    legend = [t.get_text() for t in bars.get_legend().get_texts()]
    assert any("predicted" in t for t in legend) and any("realized" in t for t in legend)
    pale, solid = bars.patches[0], bars.patches[4]  # raw's predicted bar, then raw's realized bar
    assert pale.get_alpha() is not None and pale.get_alpha() < 0.5 and solid.get_alpha() in (None, 1)
    oracle = [line for line in curves.get_lines() if line.get_label().startswith("oracle")][0]
    on, off = oracle.get_linestyle(), oracle.get_dashes() if hasattr(oracle, "get_dashes") else None
    assert on not in ("-", "solid") and oracle.get_drawstyle() == "steps-post"
    assert min(s for s, _ in style.placed_sizes(fig, COLUMN)) >= style.MIN_FONT
    plt.close(fig)


def test_robot_figures_fit_one_column():
    from probecommit.report.robot_figures import aim_error_figure, fault_sweep_figure

    rows = pd.DataFrame({"k": [1, 1, 2, 2, 5], "aim_error": [12.0, 3.0, 5.0, 2.0, 1.0], "entered": [0, 1, 1, 1, 1]})
    sweep = pd.DataFrame({"size": [0.0, 4.0, 8.0], **{f"delta_{m}{e}": [0.0, 0.1, 0.2] for m in ("optimism", "coverage")
                                                        for e in ("", "_lo", "_hi")},
                          "optimism_resolved": [False, True, True], "coverage_resolved": [False, False, True]})
    for fig in (aim_error_figure(rows, 3.0, 17.0), fault_sweep_figure(sweep, "boundary pulled inward (mm)", 8.0, "sim. error")):
        assert fig.get_size_inches()[0] == pytest.approx(COLUMN)
        small = [(s, t) for s, t in style.placed_sizes(fig, COLUMN) if s < style.MIN_FONT]
        assert not small, small
        for ax in fig.axes:  # integer axes get integer ticks only
            if ax.get_xlabel().startswith("taps"):
                assert all(float(t).is_integer() for t in ax.get_xticks())
        plt.close(fig)


def test_audit_figure_budget_axis_has_integer_ticks_and_paper_words():
    from probecommit.report.audit_report import audit_figure

    table = pd.DataFrame({"k": [1, 2, 3, 4, 5, 6, 7, 8], "method": "probe_robust", "variant": "deployed", **{
        f"{m}{s}": np.linspace(0.1, 0.9, 8) for m in ("coverage", "cluster_coverage", "escape", "optimism", "realized", "predicted")
        for s in ("", "_lo", "_hi")}})
    fig = audit_figure(table)
    texts = [t for _, t in style.text_sizes(fig)]
    for ax in fig.axes:
        assert all(float(t).is_integer() for t in ax.get_xticks()), ax.get_xticks()
        assert ax.get_ylabel() and ax.get_xlabel()
    assert any("realized Rₖ" in t for t in texts) and any("predicted R̂ₖ" in t for t in texts)
    assert not any("_" in t for t in texts)
    plt.close(fig)


def test_pipeline_diagram_is_page_wide_and_readable(tmp_path, captured):
    from probecommit.report.pipeline_diagram import pipeline_figure

    keep, figs = captured
    keep.width = DOUBLE
    png = pipeline_figure(tmp_path / "pipe.png")
    _assert_readable(figs[0], DOUBLE)
    assert png.with_suffix(".pdf").is_file()
    from probecommit.report.figures import read_caption

    assert "audit" in read_caption(png)


# ----------------------------------------------------------------------------- scene renders


def _hue_fraction(rgb: np.ndarray, kind: str) -> float:
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    masks = {"blue": (b - r > 40) & (b - g > 15), "red": (r - g > 80) & (r - b > 80),
             "orange": (r - b > 100) & (g - b > 30) & (r > 150), "green": (g - r > 40) & (g - b > 30)}
    return float(masks[kind].mean())


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    from probecommit.report.scenes import render_scenes

    out = tmp_path_factory.mktemp("scenes")
    spec = {"taps": [[-6.0, False], [3.0, True], [1.0, True], [5.0, False]], "x_hole": 2.0, "c": 1.0, "aim": 2.2}
    listing = render_scenes(out, spec)
    if not any(r["engine"] == "MuJoCo" for r in listing["renders"]):
        pytest.skip("no software OpenGL for MuJoCo (make test installs libegl1, libgl1-mesa-dri and libosmesa6): "
                    + "; ".join(s["reason"] for s in listing["skipped"])[:300])
    return out, listing, spec


@pytest.mark.slow
def test_every_scene_is_rendered_and_shows_its_object(scenes):
    from PIL import Image

    out, listing, _ = scenes
    files = {r["file"]: r for r in listing["renders"]}
    expected = {"scene_insertion_mujoco.png": ("blue", 0.25), "scene_push2d_mujoco.png": ("green", 0.01),
                "scene_darts_mujoco.png": ("red", 0.001), "scene_hinge_mujoco.png": ("green", 0.03),
                "scene_grasp_mujoco.png": ("green", 0.01), "scene_shuffleboard_drawn.png": ("blue", 0.03),
                "scene_fig1a_taps.png": ("red", 0.0003), "scene_fig1c_insertion.png": ("orange", 0.003)}
    try:
        import pybullet  # noqa: F401

        expected.update({"scene_insertion_pybullet.png": ("blue", 0.25), "scene_push2d_pybullet.png": ("green", 0.01)})
    except ImportError:
        pass
    for name, (hue, least) in expected.items():
        assert name in files, (name, listing["skipped"])
        rgb = np.asarray(Image.open(out / name).convert("RGB"))
        assert rgb.std() > 10, f"{name} is blank"
        frac = _hue_fraction(rgb, hue)
        assert frac >= least, (name, hue, frac)
    # the insertion plate: the segmentation says it fills a region, and the pixels agree with it
    plate = files["scene_insertion_mujoco.png"]["fractions"]["plate"]
    assert plate > 0.3 and abs(plate - _hue_fraction(np.asarray(Image.open(out / "scene_insertion_mujoco.png")), "blue")) < 0.25
    assert files["scene_fig1c_insertion.png"]["fractions"]["peg"] > 0.003


@pytest.mark.slow
def test_scene_figures_are_readable(scenes, tmp_path, captured):
    from probecommit.report.scene_figures import fig1_panel, fig3_scenes

    out, _, spec = scenes
    keep, figs = captured
    fig3_scenes(out, tmp_path / "fig3.png")
    _assert_readable(figs[-1], COLUMN)
    assert "drawn with matplotlib" in figs[-1]["caption"]
    assert any("SAPIEN, drawn" in t for t in figs[-1]["labels"])
    keep.width = COLUMN / 2
    for which in ("a", "c"):
        fig1_panel(out, which, spec, tmp_path / f"fig1{which}.png")
        _assert_readable(figs[-1], COLUMN / 2)
        assert (tmp_path / f"fig1{which}.pdf").is_file()


@pytest.mark.slow
def test_verify_notices_a_figure_without_its_pdf(publication, tmp_path):
    """A paper figure is published as PNG and PDF; a missing PDF fails verify, even with fresh manifests."""
    import shutil

    from probecommit.report.manifest import write_manifest, write_root_manifest
    from probecommit.report.verify import verify

    pub = tmp_path / "pub"
    shutil.copytree(publication, pub)
    root = pub / "results" / "paper"
    assert not [f for f in verify(pub, figures=False).failures if "PDF" in f]
    name = "fig_5b_hardware_simulated_rig_aim_error"
    (root / "robot" / f"{name}.pdf").unlink()
    write_manifest(root / "robot")
    write_root_manifest(root)
    assert any(f"{name}.png: a figure without its PDF" in f for f in verify(pub, figures=False).failures)
