"""MuJoCo insertion ground truth: readings, capture, scene properties, determinism, cache."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from probecommit.tasks.insertion.model import TIP_RADIUS_MM, capture_half_width, half_gap  # noqa: E402
from probecommit.tasks.insertion.sim_mujoco import (  # noqa: E402
    CHAMFER_MM,
    MujocoInsertionSimulator,
)

pytestmark = pytest.mark.mujoco

X_HOLE, C = 1.7, 1.0


@pytest.fixture(scope="module")
def sim() -> MujocoInsertionSimulator:
    return MujocoInsertionSimulator()


def test_tap_on_plate_away_from_slot_reads_top(sim):
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE + 10.0)) < 0.2
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE - 10.0)) < 0.2


def test_tap_over_slot_centre_reads_floor(sim):
    assert abs(sim.tap_reading(X_HOLE, C, X_HOLE) + 15.0) < 0.2


def test_centred_peg_enters_and_offset_peg_fails(sim):
    ok = sim.execute(np.array([X_HOLE, C]), X_HOLE)
    assert ok["realized"] == 0.0 and ok["depth"] > 14.5
    bad = sim.execute(np.array([X_HOLE, C]), X_HOLE + 3.0)
    assert bad["realized"] == 1.0 and abs(bad["depth"]) < 0.2


@pytest.mark.parametrize("c", [0.7, 1.3])
@pytest.mark.parametrize("sgn", [-1.0, 1.0])
def test_tap_boundary_sits_at_chamfer_edge(sim, c, sgn):
    """The flip sits at hg + 0.905 mm (the chamfer's outer edge), far outside hg - r."""
    x = -4.2
    edge = float(half_gap(c)) + CHAMFER_MM
    for d in (float(half_gap(c)) - TIP_RADIUS_MM + 0.3, float(half_gap(c)) + 0.5, edge - 0.05):
        assert sim.tap_reading(x, c, x + sgn * d) < -14.8, d
    for d in (edge + 0.05, float(half_gap(c)) + 1.5):
        assert sim.tap_reading(x, c, x + sgn * d) > -0.2, d


@pytest.mark.parametrize("c", [0.7, 1.3])
def test_capture_window_is_close_to_w(sim, c):
    x, w = 3.3, float(capture_half_width(c))
    for sgn in (-1.0, 1.0):
        assert sim.peg_depth(x, c, x + sgn * (w - 0.1)) > 14.5
        assert sim.peg_depth(x, c, x + sgn * (w + 0.1)) < 0.5


def test_same_inputs_bit_identical_across_objects():
    a, b = MujocoInsertionSimulator(), MujocoInsertionSimulator()
    for u in (X_HOLE + 5.3, X_HOLE + 8.0, X_HOLE - 2.0):
        r1, r2, r3 = a.tap_reading(X_HOLE, C, u), a.tap_reading(X_HOLE, C, u), b.tap_reading(X_HOLE, C, u)
        assert r1 == r2 == r3
    for aim in (X_HOLE + 1.5, X_HOLE - 2.5):
        assert a.peg_depth(X_HOLE, C, aim) == a.peg_depth(X_HOLE, C, aim) == b.peg_depth(X_HOLE, C, aim)


def test_instances_sharing_one_data_buffer_answer_as_alone():
    """Every instance's model shares one MjData; interleaving instances changes no answer."""
    rng = np.random.default_rng(3)
    truths = np.column_stack([rng.uniform(-10, 10, 6), rng.uniform(0.7, 1.3, 6)])
    queries = [(x, c, kind, q) for x, c in truths for kind in ("tap_reading", "peg_depth")
               for q in (x + rng.uniform(-3, 3), rng.uniform(-10, 10))]
    alone = [getattr(MujocoInsertionSimulator(), kind)(x, c, q) for x, c, kind, q in queries]  # a fresh buffer each
    shared = MujocoInsertionSimulator()
    order = rng.permutation(len(queries))
    interleaved = {int(i): getattr(shared, queries[i][2])(queries[i][0], queries[i][1], queries[i][3]) for i in order}
    assert [interleaved[i] for i in range(len(queries))] == alone
    assert len(shared._data) == 1  # one layout, one buffer


def test_prefetch_in_engine_threads_answers_as_one_by_one(monkeypatch):
    """Queries run ahead in engine threads give the one-by-one answers, counts and cache order."""
    rng = np.random.default_rng(5)
    truths = np.column_stack([rng.uniform(-10, 10, 5), rng.uniform(0.7, 1.3, 5)])
    keys = [("peg_depth" if i % 2 else "tap_reading", (float(x), float(c)), (float(x + rng.uniform(-3, 3)),))
            for i, (x, c) in enumerate(np.repeat(truths, 3, axis=0))]
    one_by_one = MujocoInsertionSimulator()
    expected = [one_by_one.cached_key(k) for k in keys]
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "3")
    ahead = MujocoInsertionSimulator()
    assert ahead.prefetch(keys + keys[:2]) == len(keys)  # a repeated key runs once
    assert ahead.engine_calls == one_by_one.engine_calls
    assert list(ahead._cache) == list(one_by_one._cache)
    assert all(np.array_equal(ahead.cached_key(k), v) for k, v in zip(keys, expected))
    assert ahead.engine_calls == one_by_one.engine_calls  # nothing asked twice
    assert ahead.prefetch(keys) == 0
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "1")
    assert MujocoInsertionSimulator().prefetch(keys) == 0  # threads off: answered on demand
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "two")
    with pytest.raises(ValueError, match="PROBECOMMIT_ENGINE_THREADS must be a positive integer"):
        MujocoInsertionSimulator().prefetch(keys)


def test_repeated_query_hits_cache():
    s = MujocoInsertionSimulator()
    first = s.query("tap_reading", X_HOLE, C, 3.0)
    s.query("peg_depth", X_HOLE, C, 2.0)
    calls = dict(s.engine_calls)
    assert calls == {"tap_reading": 1, "peg_depth": 1}
    assert s.query("tap_reading", X_HOLE, C, 3.0) == first
    s.query("peg_depth", X_HOLE, C, 2.0)
    assert s.engine_calls == calls


def test_probe_with_same_seed_is_identical():
    theta = np.array([X_HOLE, C])
    out = []
    for _ in range(2):
        s, rng = MujocoInsertionSimulator(noise_sigma=0.5), np.random.default_rng(123)
        out.append([s.probe(theta, u, rng)[0] for u in (-12.0, 0.0, 3.0, 6.0)])
    assert out[0] == out[1]
    assert out[0][0] != pytest.approx(0.0, abs=1e-9)  # noise was actually added


def test_module_imports_without_mujoco():
    """Importing the module needs no mujoco; constructing the simulator names the extra."""
    code = (
        "import sys; sys.modules['mujoco'] = None\n"
        "from probecommit.tasks.insertion import sim_mujoco\n"
        "from probecommit.engines import EngineUnavailableError\n"
        "try:\n"
        "    sim_mujoco.MujocoInsertionSimulator()\n"
        "except EngineUnavailableError as e:\n"
        "    assert 'probecommit[mujoco]' in str(e)\n"
        "else:\n"
        "    raise SystemExit('no error')\n"
    )
    import probecommit

    src = str(Path(probecommit.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")]))}
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
