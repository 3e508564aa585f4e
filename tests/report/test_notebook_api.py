"""The plot-first Python API (probecommit.audit_run / audit_log) and the package's public surface."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import probecommit
from probecommit.runner.study import run_study

ROOT = Path(__file__).resolve().parents[2]
ROBOT_LOG = ROOT / "tests" / "audit" / "data" / "robot_log.csv"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from tests.conftest import small_config

    out = tmp_path_factory.mktemp("api") / "run"
    run_study(small_config(), out)
    return out


def test_audit_run_gives_the_commands_numbers_tidy_and_wide(run_dir):
    from probecommit.audit.pipeline import audit

    result = probecommit.audit_run(run_dir, resamples=200, seed=3)
    expected = audit(run_dir, resamples=200, seed=3).table
    pd.testing.assert_frame_equal(result.table, expected)
    tidy = result.to_frame()
    assert list(tidy.columns[-4:]) == ["metric", "value", "lo", "hi"]
    assert {"coverage", "cluster_coverage", "escape", "realized", "predicted", "optimism"} <= set(tidy["metric"])
    # Every tidy row is a cell of the wide table, nothing recomputed.
    for _, row in tidy.sample(20, random_state=0).iterrows():
        wide = expected[(expected["method"] == row["method"]) & (expected["k"] == row["k"])].iloc[0]
        assert row["value"] == wide[row["metric"]] or (np.isnan(row["value"]) and np.isnan(wide[row["metric"]]))
        if f"{row['metric']}_lo" in expected.columns:
            assert (row["lo"], row["hi"]) == (wide[f"{row['metric']}_lo"], wide[f"{row['metric']}_hi"])
        else:
            assert np.isnan(row["lo"]) and np.isnan(row["hi"])
    assert len(tidy) == len(expected) * tidy["metric"].nunique()


def test_plot_returns_the_report_figure_and_the_notebook_shows_table_and_figure(run_dir):
    from matplotlib.figure import Figure

    result = probecommit.audit_run(run_dir, resamples=200)
    fig = result.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    assert fig.axes[0].get_title(loc="left") == "(a) coverage"  # the audit report's panel titles, in the paper's words
    page = result._repr_html_()
    assert "<table" in page and "data:image/png;base64," in page and "cluster bootstrap" in page
    assert repr(result).startswith("AuditReport(source=")


def test_audit_log_reads_a_robots_own_csv():
    result = probecommit.audit_log(ROBOT_LOG, resamples=200)
    assert result.n_total == len(pd.read_csv(ROBOT_LOG))
    assert not result.to_frame().empty


def test_audit_run_on_a_log_says_which_function_to_use(tmp_path):
    from probecommit.errors import UserError

    with pytest.raises(UserError, match="use probecommit.audit_log"):
        probecommit.audit_run(ROBOT_LOG)


def test_dir_shows_the_public_api_and_no_stray_names():
    names = dir(probecommit)
    assert {"Session", "audit_run", "audit_log", "AuditReport", "paper_config", "__version__"} <= set(names)
    assert "annotations" not in names
    for name in names:
        getattr(probecommit, name)


def test_session_imports_where_fcntl_does_not_exist():
    """Windows has no fcntl: the robot API must import there (the lock is taken when a log is opened)."""
    code = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name == 'fcntl':
            raise ImportError('no fcntl here')
sys.modules.pop('fcntl', None)
sys.meta_path.insert(0, Block())
import probecommit
print(probecommit.Session.__name__)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "Session"


def test_the_gru_extra_names_no_exact_torch_build():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    gru = project["optional-dependencies"]["gru"]
    assert gru == ["torch>=2"]
    assert not any("==" in dep for deps in project["optional-dependencies"].values() for dep in deps)
    assert any(line.startswith("torch==") for line in (ROOT / "constraints.txt").read_text().splitlines())


def test_nothing_points_to_a_design_file_the_repository_lacks():
    missing = "DESIGN" + ".md"
    assert not (ROOT / missing).exists()
    offenders = []
    for folder in ("src", "tests", "docs", "examples", "benchmarks"):
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in (".py", ".md", ".yaml", ".toml", ".txt") and missing in path.read_text(errors="ignore"):
                offenders.append(str(path.relative_to(ROOT)))
    for name in ("README.md", "pyproject.toml", "Makefile"):
        if missing in (ROOT / name).read_text():
            offenders.append(name)
    assert offenders == []
