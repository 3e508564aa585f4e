"""Figures are drawn at the paper's column widths with fonts of at least 7 pt, as PNG and PDF."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from probecommit.report import style
from probecommit.report.audit_report import audit_figure, gates_figure
from probecommit.report.figures import save_figure
from probecommit.report.study_figures import fault_signatures


def font_sizes(fig) -> list[float]:
    return [t.get_fontsize() for t in fig.findobj(lambda a: hasattr(a, "get_fontsize") and hasattr(a, "get_text"))
            if getattr(a := t, "get_text", lambda: "")()]


def check(fig, width: float) -> None:
    assert fig.get_size_inches()[0] == pytest.approx(width)
    sizes = font_sizes(fig)
    assert sizes and min(sizes) >= style.MIN_FONT, min(sizes)


def test_fault_signatures_one_visible_line_per_fault(tmp_path):
    rows = [{"fault": f, "k": k, "escape": 0.1, "coverage": 0.9, "optimism": 0.0, "failure": 0.2}
            for f in ("none", "noise", "boundary", "prior", "particles", "frame") for k in range(1, 9)]
    captured = {}
    real_save = save_figure

    def keep(fig, path, **kwargs):
        captured["fig"] = fig
        return real_save(fig, path, **kwargs)

    import probecommit.report.study_figures as sf

    sf.save_figure = keep
    try:
        png = fault_signatures(pd.DataFrame(rows), tmp_path / "sig.png")
    finally:
        sf.save_figure = real_save
    fig = captured["fig"]
    assert png.suffix == ".png" and png.with_suffix(".pdf").is_file()
    check(fig, style.COLUMN)  # the paper sets it in one column
    lines = [l for l in fig.axes[0].get_lines()]
    # identical data: every fault still distinguishable by colour, style or marker and an x offset
    keys = {(l.get_color(), str(l.get_linestyle()), l.get_marker(), round(float(l.get_xdata()[0]), 3)) for l in lines}
    assert len(keys) == 6


def test_the_oracle_is_drawn_as_a_step(tmp_path):
    curves = pd.DataFrame({"signal": ["oracle"] * 3 + ["raw"] * 2, "commit_rate": [0.2, 0.6, 1.0, 0.5, 1.0],
                           "failure": [0.0, 0.0, 0.4, 0.3, 0.4], "tau": [0, 1, 2, 0, 1]})

    class Result:
        pass

    result = Result()
    result.curves = curves
    result.summary = pd.DataFrame({"signal": ["raw"], "claimed": [0.1], "realized": [0.3]})
    fig = gates_figure(result)
    check(fig, style.COLUMN)
    oracle = [l for l in fig.axes[0].get_lines() if l.get_label().startswith("oracle")][0]
    assert oracle.get_drawstyle() == "steps-post"
    plt.close(fig)


def test_audit_figure_width_and_fonts():
    table = pd.DataFrame({"k": [1, 2], "method": "probe_robust", "variant": "deployed", **{
        f"{m}{s}": [0.5, 0.6] for m in ("coverage", "cluster_coverage", "escape", "optimism", "realized", "predicted")
        for s in ("", "_lo", "_hi")}})
    fig = audit_figure(table)
    check(fig, style.DOUBLE)
    plt.close(fig)
