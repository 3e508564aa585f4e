"""The shared simulator bases: noise validated once, a target miss scored the same way for every family."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.tasks.base import NoisySimulator, TargetMissSimulator


class Ramp(TargetMissSimulator):
    engine, family = "toy", "ramp"
    query, outcome, target = "slide", "stop", "target distance"
    not_finite = "toy ramp broke at {action}"

    def slide(self, a: float, u: float) -> float:
        return a * u if u >= 0 else float("nan")


def test_noise_is_validated_once_for_every_simulator():
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="noise_sigma must be >= 0"):
            NoisySimulator(bad)
    assert NoisySimulator(0.0).noise_sigma == 0.0


def test_probe_and_miss_from_one_cached_query():
    sim = Ramp(noise_sigma=0.0)
    theta = np.array([2.0])
    assert sim.probe(theta, np.array([3.0]), np.random.default_rng(0))[0] == 6.0
    assert sim.execute(theta, np.array([1.5]), np.array([2.0])) == {"realized": 1.0, "stop": 3.0}
    assert sim.engine_calls == {"slide": 2}
    with pytest.raises(ValueError, match="the ramp outcome needs the target distance"):
        sim.execute(theta, np.array([1.5]))
    with pytest.raises(FloatingPointError, match=r"toy ramp broke at \[-1.0\]"):
        sim.execute(theta, np.array([-1.0]), np.array([2.0]))


def test_simulators_of_one_ground_truth_share_engine_answers_inside_the_block_only():
    from probecommit.tasks.base import shared_engine_answers
    from probecommit.tasks.insertion import SPEC

    InsertionConfig = SPEC.config
    from probecommit.tasks.registry import build_simulator

    analytic = InsertionConfig.model_validate({"simulator": {"engine": "analytic"}})
    other = InsertionConfig.model_validate({"simulator": {"engine": "analytic", "boundary_offset": 0.3}})
    theta, aim = np.array([1.5, 1.0]), np.array([2.0])

    def depth_calls(sim):
        sim.execute(theta, aim)
        return sim.engine_calls.get("peg_depth", 0)

    with shared_engine_answers():
        first, second, shifted = (build_simulator("insertion", c) for c in (analytic, analytic, other))
        assert depth_calls(first) == 1
        assert depth_calls(second) == 0  # answered from the shared store
        assert second.cache_records() == first.cache_records()  # still recorded as its own
        assert depth_calls(shifted) == 1  # another ground truth shares nothing
        with shared_engine_answers():  # nested: the same store
            assert depth_calls(build_simulator("insertion", analytic)) == 0
    assert depth_calls(build_simulator("insertion", analytic)) == 1  # outside: its own engine


def test_settings_applied_outside_the_queries_do_not_split_the_shared_answers():
    from probecommit.tasks.base import shared_engine_answers
    from probecommit.tasks.insertion import SPEC

    InsertionConfig = SPEC.config
    from probecommit.tasks.registry import build_simulator

    clean = InsertionConfig.model_validate({"simulator": {"engine": "analytic", "noise_sigma": 0.0}})
    noisy = InsertionConfig.model_validate({"simulator": {"engine": "analytic", "noise_sigma": 2.0}})
    offset = InsertionConfig.model_validate({"simulator": {"engine": "analytic", "aim_offset": 0.5}})
    theta = np.array([1.5, 1.0])
    with shared_engine_answers():
        first, louder, shifted = (build_simulator("insertion", c) for c in (clean, noisy, offset))
        first.execute(theta, np.array([2.5]))
        first.probe(theta, np.array([1.0]), np.random.default_rng(0))
        louder.probe(theta, np.array([1.0]), np.random.default_rng(0))
        shifted.execute(theta, np.array([2.0]))  # the engine is asked for aim 2.5, already answered
        assert louder.engine_calls["tap_reading"] == 0 and shifted.engine_calls["peg_depth"] == 0
        # The noise is still each simulator's own: the same draw, a reading scaled by its sigma.
        assert first.probe(theta, np.array([1.0]), np.random.default_rng(3))[0] != \
            louder.probe(theta, np.array([1.0]), np.random.default_rng(3))[0]


class ThreadedToy(NoisySimulator):
    """A thread-safe toy engine whose query fails at one argument."""

    engine = "toy"
    parallel_queries = True

    def __init__(self) -> None:
        super().__init__(0.0)
        import threading

        self.threads: set[str] = set()
        self._lock = threading.Lock()

    def depth(self, x: float, a: float) -> float:
        import threading

        with self._lock:
            self.threads.add(threading.current_thread().name)
        if a == 3.0:
            raise RuntimeError("toy engine failed at a = 3")
        return x * a


def test_prefetch_runs_in_engine_threads_and_leaves_a_failing_query_to_its_caller(monkeypatch):
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    sim = ThreadedToy()
    keys = [("depth", (2.0,), (float(a),)) for a in (1, 2, 3, 4, 2)]
    assert sim.prefetch(keys) == 3  # 1, 2, 4 answered; 3 failed; the repeated 2 ran once
    assert sim.engine_calls == {"depth": 3}
    assert all(name.startswith("probecommit-engine") for name in sim.threads)
    assert [float(sim.cached_key(k)[0]) for k in keys if k[2] != (3.0,)] == [2.0, 4.0, 8.0, 4.0]
    with pytest.raises(RuntimeError, match="toy engine failed at a = 3"):
        sim.cached_key(keys[2])  # asked on demand, it raises where the caller handles it
    assert sim.engine_calls == {"depth": 3}
    assert not NoisySimulator.parallel_queries  # the default stays off
    assert NoisySimulator(0.0).prefetch(keys) == 0


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="needs fork")
def test_a_forked_child_makes_its_own_engine_threads(monkeypatch):
    """The parent's pool has no threads in a forked child: the child prefetches with a new one."""
    import os

    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    keys = [("depth", (2.0,), (float(a),)) for a in (1, 2, 4)]
    assert ThreadedToy().prefetch(keys) == 3  # the parent's pool exists now
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child reports through the pipe
        try:
            os.write(write, str(ThreadedToy().prefetch(keys)).encode())
        finally:
            os._exit(0)
    os.close(write)
    _, status = os.waitpid(pid, 0)
    assert os.read(read, 16) == b"3" and status == 0


def test_a_loaded_engine_cache_is_stored_once_per_distinct_value_and_written_back_exactly():
    """load_cache shares equal latents, args and answers (matched by their bytes: -0.0 stays -0.0);
    answers are read-only, so no caller can change what later queries read."""
    from probecommit.store.schema import cache_frame, cache_records

    records = [{"engine": "toy", "query": "slide", "theta": [-0.0], "arg": [u], "value": [1.5]} for u in (1.0, 2.0)]
    records.append({"engine": "toy", "query": "slide", "theta": [2.0], "arg": [1.0], "value": [1.5]})
    records.append({"engine": "other", "query": "slide", "theta": [3.0], "arg": [1.0], "value": [0.0]})
    sim = Ramp(noise_sigma=0.0)
    sim.load_cache(cache_records(cache_frame(records, ("a",)), ("a",)))
    back = sim.cache_records()
    assert back == records[:3]
    assert [np.signbit(r["theta"][0]) for r in back] == [True, True, False]
    keys, values = list(sim._cache), list(sim._cache.values())
    assert keys[0][1] is keys[1][1] and keys[0][2] is keys[2][2]  # one tuple per distinct latent / arg
    assert values[0] is values[1] is values[2]
    with pytest.raises(ValueError, match="read-only"):
        values[0][0] = 0.0
    fresh = sim.cached("slide", [3.0], [2.0])
    assert fresh[0] == 6.0 and not fresh.flags.writeable
    assert sim.engine_calls == {"slide": 1}


def _loaded(records) -> tuple[list, list, list]:
    """A fresh simulator's cache after ``load_cache(records)``: the keys taken, the cache's keys and values."""
    sim = Ramp(noise_sigma=0.0)
    taken = sim.load_cache(records)
    return taken, list(sim._cache), list(sim._cache.values())


def _bits(key: tuple) -> tuple:
    """A cache key with its floats as bytes."""
    return key[0], np.array(key[1], dtype=float).tobytes(), np.array(key[2], dtype=float).tobytes()


def _sharing(objects: list) -> list[int]:
    """Which earlier object each one is (the index of its first occurrence by identity)."""
    return [next(i for i, other in enumerate(objects) if other is obj) for obj in objects]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["toy", "other"]), st.sampled_from(["slide", "coast"]),
                          st.sampled_from([0.0, -0.0, 1.5, float("nan"), float("inf")]),
                          st.sampled_from([0.0, -0.0, 2.0]), st.sampled_from([0.0, -0.0, 1.0, float("nan")])),
                max_size=12))
def test_answers_loaded_as_columns_are_the_records_loaded_one_by_one(rows):
    """``load_cache`` of ``AnswerColumns`` (a whole column at once) takes the same keys, answers
    (bit for bit, read-only) and shares the same tuples and arrays as the same answers given one
    record at a time: -0.0 apart from 0.0, another engine's rows skipped, a repeated key the last."""
    from probecommit.tasks.base import AnswerColumns

    def columns(width: int, at: int) -> np.ndarray:
        return np.array([[row[at]] * width for row in rows], dtype=float).reshape(len(rows), width)

    answers = AnswerColumns([r[0] for r in rows], [r[1] for r in rows], columns(2, 2), columns(1, 3), columns(1, 4))
    whole, one_by_one = _loaded(answers), _loaded(list(answers))
    for keys in (0, 1):  # compared by their bits (a NaN equals no other NaN object)
        assert [_bits(key) for key in whole[keys]] == [_bits(key) for key in one_by_one[keys]]
    assert [v.tobytes() for v in whole[2]] == [v.tobytes() for v in one_by_one[2]]
    assert all(not v.flags.writeable and v.shape == (1,) for v in whole[2])
    for part in (1, 2):
        assert _sharing([key[part] for key in whole[1]]) == _sharing([key[part] for key in one_by_one[1]])
    assert _sharing(whole[2]) == _sharing(one_by_one[2])


def test_cached_answers_are_copies_so_the_engines_and_callers_arrays_stay_writable():
    class Buffered(NoisySimulator):
        engine = "toy"

        def __init__(self):
            super().__init__(0.0)
            self.buffer = np.zeros(2)

        def reading(self, a: float) -> np.ndarray:
            self.buffer[:] = a  # an engine writing its own buffer, then returning it
            return self.buffer

    sim = Buffered()
    first = sim.cached("reading", [1.0], [])
    second = sim.cached("reading", [2.0], [])
    assert first.tolist() == [1.0, 1.0] and second.tolist() == [2.0, 2.0] and sim.buffer.flags.writeable
    value = np.array([4.0])
    sim.load_cache([{"engine": "toy", "query": "reading", "theta": [3.0], "arg": [], "value": value}])
    assert value.flags.writeable and sim.cached("reading", [3.0], []).tolist() == [4.0]
