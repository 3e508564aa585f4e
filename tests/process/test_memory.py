"""Memory estimates refuse what does not fit; freed heap memory goes back to the system."""

import platform
import sys

import numpy as np
import pytest

from probecommit.process import memory


def test_check_fits_refuses_with_the_estimate_and_the_setting(monkeypatch):
    monkeypatch.setattr(memory, "available_bytes", lambda: 4 * 1024**3)
    memory.check_fits(1.9 * 1024**3, "the beliefs of one unit", "belief.particles")  # under half: fine
    with pytest.raises(MemoryError, match=r"the beliefs of one unit would need about 2\.5 GiB, more than half the "
                                          r"4\.0 GiB available \(host or container limit, the smaller\); reduce belief\.particles"):
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


#: Three 6 MB arrays made, used and freed per step, as a filter step's weights and particles are.
_STEPS = """
import os, resource, sys
import numpy as np
from probecommit.process import memory
taken = memory.reuse_freed_arrays() if sys.argv[1] == "reuse" else None
def step():
    arrays = [np.ones(750_000) for _ in range(3)]
    return sum(float(a[-1]) for a in arrays)
step()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    step()
print(taken, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before,
      os.environ.get("MALLOC_MMAP_THRESHOLD_"), os.environ.get("MALLOC_TRIM_THRESHOLD_"), os.environ.get("MALLOC_ARENA_MAX"))
"""


def _steps(mode: str, **env: str) -> list[str]:
    import os
    import subprocess

    clean = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    done = subprocess.run([sys.executable, "-c", _STEPS, mode], capture_output=True, text=True, check=True,
                          env={**clean, **env})
    return done.stdout.split()


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc" or memory._mallopt() is None, reason="the thresholds are glibc's")
def test_reuse_freed_arrays_keeps_a_steps_arrays_in_the_heap():
    # glibc's defaults return the freed arrays past its trim threshold, so each step faults in
    # fresh pages (~900 per step here); with the command's thresholds the heap reuses them.
    _, default_faults, *_ = _steps("default")
    taken, reuse_faults, mmap_env, trim_env, arenas_env = _steps("reuse")
    assert taken == "True"
    assert (mmap_env, trim_env, arenas_env) == (str(memory.HEAP_REUSE_BYTES), str(memory.HEAP_TOP_BYTES),
                                                str(memory.HEAP_ARENAS))  # exported to workers
    assert int(default_faults) > 5000 and int(reuse_faults) < 500, (default_faults, reuse_faults)


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc" or memory._mallopt() is None, reason="the thresholds are glibc's")
def test_reuse_freed_arrays_leaves_a_threshold_the_user_set():
    _, _, mmap_env, trim_env, arenas_env = _steps("reuse", MALLOC_TRIM_THRESHOLD_="131072", MALLOC_ARENA_MAX="4")
    assert trim_env == "131072" and arenas_env == "4" and mmap_env == str(memory.HEAP_REUSE_BYTES)


def test_reuse_freed_arrays_without_mallopt(monkeypatch):
    monkeypatch.setattr(memory, "_mallopt", lambda: None)
    assert memory.reuse_freed_arrays() is False


#: Whether a 3 MiB array gets pages of its own (glibc's mallinfo2: bytes in mmapped blocks), before,
#: inside, inside a nested block of a 4 MiB threshold, after that block, and after ``large_arrays_apart``;
#: then within ``large_arrays_in_heap`` (whether a block there changed the threshold, and the array), and after.
_APART = """
import ctypes, sys
import numpy as np
from probecommit.process import memory
if sys.argv[1] == "reuse":
    memory.reuse_freed_arrays()
class Info(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
mallinfo2 = ctypes.CDLL(None).mallinfo2
mallinfo2.restype = Info
def apart():
    memory.trim_heap()  # no free block left at the heap's top to take the array from
    before = mallinfo2().hblkhd
    block = np.ones(3 * 2**20 // 8)
    return mallinfo2().hblkhd - before >= block.nbytes
outside = apart()
with memory.large_arrays_apart() as changed:
    inside = apart()
    with memory.large_arrays_apart(4 * 2**20):
        nested = apart()
    back = apart()
after = apart()
with memory.large_arrays_in_heap(), memory.large_arrays_apart() as kept_changed:
    kept = apart()
print(changed, outside, inside, nested, back, after, kept_changed, kept, apart())
"""


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc" or memory._mallopt() is None, reason="the thresholds are glibc's")
def test_large_arrays_apart_maps_large_arrays_only_within_and_only_under_the_commands_setting():
    import os
    import subprocess

    def run(mode: str, **env: str) -> list[str]:
        clean = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
        return subprocess.run([sys.executable, "-c", _APART, mode], capture_output=True, text=True, check=True,
                              env={**clean, **env}).stdout.split()

    # changed, outside, inside, nested, back, after: the command's 32 MiB threshold keeps 3 MiB in the heap
    # but within; a nested block's threshold (4 MiB) holds within it only, then the enclosing one's again.
    # Within large_arrays_in_heap a block changes nothing (the array stays in the heap), and after it, neither.
    assert run("reuse") == ["True", "False", "True", "False", "True", "False", "False", "False", "False"]
    # A threshold the user chose is theirs: left alone (here 1 MiB: every 3 MiB array is mapped).
    assert run("reuse", MALLOC_MMAP_THRESHOLD_="1048576") == ["False", "True", "True", "True", "True", "True",
                                                              "False", "True", "True"]
    # A program that never took the command's setting keeps glibc's dynamic threshold.
    assert run("plain")[0] == "False"
