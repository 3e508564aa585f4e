"""A scratch publication, built once per test session (quick insertion, breadth, cost and robot)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def publication(tmp_path_factory) -> Path:
    """``reproduce insertion breadth cost robot --quick`` published into a scratch folder (DIR/results/paper)."""
    from probecommit.report import paper
    from probecommit.report.publish import publish

    base = tmp_path_factory.mktemp("scratch")
    done = paper.reproduce(["insertion", "breadth", "cost", "robot"], base / "runs", quick=True)
    publish(done["targets"], base / "pub", timing=done)
    return base / "pub"


@pytest.fixture(scope="session")
def explain_publication(tmp_path_factory) -> Path:
    """``reproduce insertion breadth cost explain --quick`` (engines and GRU come with explain) published into a
    scratch folder: the explain step's stored tables beside its results."""
    from probecommit.report import paper
    from probecommit.report.publish import publish

    base = tmp_path_factory.mktemp("scratch_explain")
    done = paper.reproduce(["insertion", "breadth", "cost", "explain"], base / "runs", quick=True)
    publish(done["targets"], base / "pub", timing=done)
    return base / "pub"
