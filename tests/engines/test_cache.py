"""engines.cache.InstanceCache: built once per key, least recently used dropped, eviction called."""

from __future__ import annotations

import pytest

from probecommit.engines.cache import InstanceCache


def test_lru_builds_once_and_evicts_the_least_recently_used():
    built, evicted = [], []
    cache = InstanceCache(lambda a, b: built.append((a, b)) or f"{a:g}-{b:g}", 2, evict=lambda k, v: evicted.append((k, v)))
    assert cache.get(1, 2) == "1-2" and cache.get(1.0, 2.0) == "1-2"  # keys are floats: built once
    cache.get(3, 4)
    cache.get(1, 2)  # now (3, 4) is the least recently used
    cache.get(5, 6)
    assert built == [(1.0, 2.0), (3.0, 4.0), (5.0, 6.0)]
    assert evicted == [((3.0, 4.0), "3-4")]
    assert (1, 2) in cache and (3, 4) not in cache and len(cache) == 2
    assert cache.values() == ["1-2", "5-6"]
    cache.clear()
    assert len(cache) == 0 and evicted == [((3.0, 4.0), "3-4")]


def test_size_must_be_positive():
    with pytest.raises(ValueError, match="cache size"):
        InstanceCache(lambda: None, 0)


def test_a_simulator_and_its_engine_instances_go_as_soon_as_it_is_dropped():
    import gc
    import weakref

    class Simulator:
        def __init__(self):
            self._instance = InstanceCache(self._compile, 4, evict=self._drop).get

        def _compile(self, x):
            return [x]

        def _drop(self, key, entry):
            pass

    gc.disable()  # no collector: only reference counts may free it
    try:
        sim = Simulator()
        entry = sim._instance(1.0)
        alive = weakref.ref(sim)
        del sim
        assert alive() is None  # no reference cycle through the cache's bound builder
    finally:
        gc.enable()
    assert entry == [1.0]
    orphan = InstanceCache(Simulator()._compile, 4)  # its owner is gone at once
    with pytest.raises(ReferenceError, match="no longer exists"):
        orphan.get(1.0)
