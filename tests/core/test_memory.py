"""Memory estimates refuse what does not fit; freed heap memory goes back to the system."""

import sys

import numpy as np
import pytest

from probecommit.core import memory


def test_check_fits_refuses_with_the_estimate_and_the_setting(monkeypatch):
    monkeypatch.setattr(memory, "available_bytes", lambda: 4 * 1024**3)
    memory.check_fits(1.9 * 1024**3, "the beliefs of one unit", "belief.particles")  # under half: fine
    with pytest.raises(MemoryError, match=r"the beliefs of one unit would need about 2\.5 GiB, more than half the "
                                          r"4\.0 GiB available; reduce belief\.particles"):
        memory.check_fits(2.5 * 1024**3, "the beliefs of one unit", "belief.particles")


def _rss_kib() -> int:
    with open("/proc/self/status") as handle:
        return next(int(line.split()[1]) for line in handle if line.startswith("VmRSS:"))


@pytest.mark.skipif(not sys.platform.startswith("linux") or memory._malloc_trim() is None,
                    reason="malloc_trim is glibc's")
def test_release_free_heap_returns_freed_small_blocks():
    # Many small arrays live in glibc's heap (below its mmap threshold); one survivor at the
    # top keeps free() from shrinking the heap, so the freed pages stay resident until trimmed.
    blocks = [np.ones(2_000) for _ in range(12_000)]  # ~16 KB each, ~190 MB in all
    survivor = blocks[-1]
    del blocks
    before = _rss_kib()
    assert memory.release_free_heap() is True
    after = _rss_kib()
    assert before - after > 120 * 1024, (before, after)  # most of the ~190 MB went back
    assert survivor.sum() == 2_000.0


def test_release_free_heap_without_malloc_trim(monkeypatch):
    monkeypatch.setattr(memory, "_malloc_trim", lambda: None)
    assert memory.release_free_heap() is False
