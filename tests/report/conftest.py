"""A scratch publication, built once per test session (quick insertion, breadth, cost and robot)."""

from __future__ import annotations

import fcntl
import shutil
from pathlib import Path

import pytest


def built_once(request, name: str, targets: list[str]) -> Path:
    """``reproduce TARGETS --quick`` published into DIR/pub, once per run of the suite, returns DIR/pub.

    Under pytest-xdist (make test runs two workers) each worker has its own session, so a session fixture would be
    built once per worker that uses it. The first worker to ask builds it into the run's shared temporary folder
    under a lock; a worker asking meanwhile waits and reads the same files, never a half-written copy (the tests
    copy it before editing)."""
    from probecommit.report import paper
    from probecommit.report.publish import publish

    def build(base: Path) -> Path:
        done = paper.reproduce(targets, base / "runs", quick=True)
        publish(done["targets"], base / "pub", timing=done)
        return base / "pub"

    factory = request.getfixturevalue("tmp_path_factory")
    if not hasattr(request.config, "workerinput"):  # not an xdist worker (a worker's config has its input)
        return build(factory.mktemp(name))
    shared = factory.getbasetemp().parent  # the run's folder, above every worker's own
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, also if the build raised
        if not (shared / name / "built").is_file():
            shutil.rmtree(shared / name, ignore_errors=True)
            build(shared / name)
            (shared / name / "built").touch()
    return shared / name / "pub"


@pytest.fixture(scope="session")
def publication(request) -> Path:
    """``reproduce insertion breadth cost robot --quick`` published into a scratch folder (DIR/results/paper)."""
    return built_once(request, "scratch", ["insertion", "breadth", "cost", "robot"])


@pytest.fixture(scope="session")
def explain_publication(request) -> Path:
    """``reproduce insertion breadth cost explain --quick`` (engines and GRU come with explain) published into a
    scratch folder: the explain step's stored tables beside its results. Its tamper cases run in two xdist groups
    (tests/report/test_verify_explain.py), which share this one build."""
    return built_once(request, "scratch_explain", ["insertion", "breadth", "cost", "explain"])


@pytest.fixture(scope="session")
def publication_report(publication):
    """``verify`` of the untouched scratch publication, figures drawn again: read by every test that checks the
    clean publication passes (each such verify takes seconds of figure drawing, and gives the same report)."""
    from probecommit.report.verify import verify

    return verify(publication)
