"""SAPIEN (PhysX) insertion ground truth: hand readings, capture, determinism, quiet import."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("sapien")

from probecommit.tasks.insertion.model import capture_half_width, half_gap  # noqa: E402
from probecommit.tasks.insertion.sim_mujoco import CHAMFER_MM  # noqa: E402
from probecommit.tasks.insertion.sim_pybullet import plate_boxes  # noqa: E402
from probecommit.tasks.insertion.sim_sapien import SapienInsertionSimulator  # noqa: E402

X_HOLE, C = 1.7, 1.0
SIGMA = 0.5  # mm: the tap noise; a hand reading must be within it


@pytest.fixture(scope="module")
def sim():
    s = SapienInsertionSimulator()
    yield s
    s.close()


def _env() -> dict[str, str]:
    import probecommit

    src = str(Path(probecommit.__file__).resolve().parents[1])
    return {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")]))}


def test_tap_over_plate_reads_top_and_over_slot_reads_floor(sim):
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE + 10.0)) < SIGMA
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE - 10.0)) < SIGMA
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE) + 15.0) < SIGMA


def test_tap_on_chamfer_slides_in(sim):
    """Inside the chamfer's outer edge the frictionless tip slides down to the floor."""
    hg = float(half_gap(C))
    assert sim.tap_reading(X_HOLE, C, X_HOLE + hg + 0.5 * CHAMFER_MM) < -15.0 + SIGMA
    assert sim.tap_reading(X_HOLE, C, X_HOLE - hg - 1.5) > -SIGMA


def test_centred_peg_enters_and_peg_3mm_off_does_not(sim):
    ok = sim.execute(np.array([X_HOLE, C]), X_HOLE)
    assert ok["realized"] == 0.0 and abs(ok["depth"] - 15.0) < SIGMA
    bad = sim.execute(np.array([X_HOLE, C]), X_HOLE + 3.0)
    assert bad["realized"] == 1.0 and abs(bad["depth"]) < SIGMA
    assert 3.0 > capture_half_width(C)


def test_same_query_bit_identical_on_repeat_and_across_objects(sim):
    queries = [("tap_reading", X_HOLE + 5.4), ("tap_reading", X_HOLE - 5.6), ("peg_depth", X_HOLE + 1.2)]
    first = [getattr(sim, k)(X_HOLE, C, q) for k, q in queries]
    sim.tap_reading(-4.0, 0.8, 0.0)  # another instance in between
    again = [getattr(sim, k)(X_HOLE, C, q) for k, q in queries]
    fresh = SapienInsertionSimulator()
    other = [getattr(fresh, k)(X_HOLE, C, q) for k, q in queries]
    assert first == again == other


def test_box_plate_has_the_same_tap_boundary_and_a_seam_snag():
    """MuJoCo's box decomposition: same tap answers; PhysX catches a peg corner on the
    chamfer/wall seam (why the default plate is one convex prism per side)."""
    boxes = SapienInsertionSimulator(plate="boxes")
    hg = float(half_gap(C))
    assert boxes.tap_reading(X_HOLE, C, X_HOLE + hg + 0.5 * CHAMFER_MM) < -15.0 + SIGMA
    assert abs(boxes.peg_depth(X_HOLE, C, X_HOLE + 1.0) - CHAMFER_MM) < 0.01


def test_prisms_have_the_box_plate_surface():
    """Each prism's corners are the wall/top/chamfer boxes' outer corners."""
    from probecommit.tasks.insertion.sim_sapien import plate_prisms

    boxes = {b["name"]: b for b in plate_boxes(X_HOLE, C)}
    (lc, lv), (rc, rv) = plate_prisms(X_HOLE, C, 0.02)
    right = rv + rc
    wall, top = boxes["right_wall"], boxes["right_top"]
    assert np.isclose(right[:, 0].min(), wall["pos"][0] - wall["half"][0], atol=1e-12)  # slot face
    assert np.isclose(right[:, 0].max(), top["pos"][0] + top["half"][0], atol=1e-12)  # plate end
    assert np.isclose(right[:, 2].max(), 0.0, atol=1e-12) and np.isclose(right[:, 2].min(), -0.015, atol=1e-12)
    chamfer_top = top["pos"][0] - top["half"][0]  # chamfer's outer edge on the plate top
    assert np.isclose(sorted(set(np.round(right[right[:, 2] > -1e-12, 0], 12)))[0], chamfer_top, atol=1e-12)
    left = lv + lc
    assert np.isclose(left[:, 0].max(), (X_HOLE - float(half_gap(C))) * 1e-3, atol=1e-12)  # left slot face
    assert np.isclose(left[:, 0].min(), boxes["left_top"]["pos"][0] - boxes["left_top"]["half"][0], atol=1e-12)


def test_import_and_first_query_print_nothing(capfd):
    code = (
        "from probecommit.tasks.insertion.sim_sapien import SapienInsertionSimulator\n"
        "s = SapienInsertionSimulator(); s.tap_reading(0.0, 1.0, 0.0); s.close()\n"
    )
    out = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True, text=True, check=True)
    assert out.stdout == "" and out.stderr == ""
    captured = capfd.readouterr()
    assert "libvulkan" not in captured.out + captured.err
