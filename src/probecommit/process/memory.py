"""Memory estimates before large allocations (refuse with the number and the setting to
change), the C heap's reuse of freed arrays, and handing freed heap memory back to the system
between long phases."""

from __future__ import annotations

import contextlib
import ctypes
import functools
import gc
import os
from typing import Callable, Iterator

#: Share of the available memory one allocation may take.
SHARE = 0.5


def _host_available() -> int:
    """The host's ``MemAvailable`` (8 GiB when it cannot be read)."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 * 1024**3


def _read_int(path: str) -> int | None:
    try:
        with open(path) as handle:
            text = handle.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None  # "max": no limit


#: A cgroup limit at or above this is "no limit" (cgroup v1 reports ~2**63 for none).
_NO_LIMIT = 1 << 60


def cgroup_headroom(root: str = "/sys/fs/cgroup", proc_cgroup: str = "/proc/self/cgroup") -> int | None:
    """Bytes this process's container (cgroup v2 or v1) may still use: limit minus usage; None when
    there is no limit. A container kills a process at its limit whatever the host has free."""
    paths: dict[str, str] = {}
    try:
        with open(proc_cgroup) as handle:
            for line in handle:
                _, controllers, path = line.rstrip("\n").split(":", 2)
                for name in controllers.split(",") if controllers else [""]:
                    paths[name] = path.lstrip("/")
    except (OSError, ValueError):
        pass
    candidates = []
    v2 = paths.get("", "")
    for folder in dict.fromkeys([os.path.join(root, v2), root]):  # v2: the process's group, then the root
        candidates.append((os.path.join(folder, "memory.max"), os.path.join(folder, "memory.current")))
    v1 = paths.get("memory", "")
    for folder in dict.fromkeys([os.path.join(root, "memory", v1), os.path.join(root, "memory")]):
        candidates.append((os.path.join(folder, "memory.limit_in_bytes"), os.path.join(folder, "memory.usage_in_bytes")))
    headrooms = []
    for limit_file, usage_file in candidates:
        limit = _read_int(limit_file)
        if limit is None or limit >= _NO_LIMIT:
            continue
        headrooms.append(max(0, limit - (_read_int(usage_file) or 0)))
    return min(headrooms) if headrooms else None


def available_bytes() -> int:
    """Memory this process may still use: the host's available memory, or the container's (cgroup)
    headroom when that is smaller."""
    host = _host_available()
    room = cgroup_headroom()
    return host if room is None else min(host, room)


def check_fits(needed_bytes: float, what: str, setting: str) -> None:
    """Raise ``MemoryError`` with one line when ``needed_bytes`` exceeds half the available memory
    (the container's limit counted: :func:`available_bytes`).

    Args:
        needed_bytes: The estimate.
        what: What would be allocated ("the particle beliefs of one work unit").
        setting: What to change ("belief.particles or unit_instances").
    """
    available = available_bytes()
    limit = SHARE * available
    if needed_bytes > limit:
        raise MemoryError(f"{what} would need about {needed_bytes / 1024**3:.1f} GiB, more than half the "
                          f"{available / 1024**3:.1f} GiB available (host or container limit, the smaller); "
                          f"reduce {setting}")


def _libc_function(name: str, argtypes: list) -> Callable[..., int] | None:
    """The C library's function ``name`` returning an int, or None where it has none (macOS, musl)."""
    try:
        function = getattr(ctypes.CDLL(None), name)  # the symbols already loaded: no library search
    except (OSError, AttributeError):
        return None
    function.argtypes, function.restype = argtypes, ctypes.c_int
    return function


@functools.lru_cache(maxsize=1)
def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, or None where the C library has none."""
    return _libc_function("malloc_trim", [ctypes.c_size_t])


#: glibc's ``mallopt`` parameters (malloc.h).
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _M_ARENA_MAX = -1, -3, -8
#: Freed blocks up to this size stay in the heap for reuse (larger ones get pages of their own).
HEAP_REUSE_BYTES = 32 * 1024**2
#: Free memory at the heap's top kept for the next step instead of handed back at each free.
#: A batch step's arrays together (E = 384, N = 1024: tens of MB, more with resample-move) come
#: and go every step; at a 32 MiB trim threshold the resample-move arm's larger footprint was
#: handed back and faulted in again each round (5700 faults, 3 us per episode-step of the next arm,
#: ``benchmarks/belief.py``). The explicit trims between chunks and phases still bound the peak.
HEAP_TOP_BYTES = 256 * 1024**2
#: Heaps (glibc "arenas") the threads of a process allocate from: one. glibc gives each new thread
#: a heap of its own (up to 8 per core), and each heap keeps up to :data:`HEAP_TOP_BYTES` of freed
#: memory until the next explicit trim: a replay's trace thread (the next chunk's beliefs), the
#: engine and commit threads can each hold their last chunk's freed temporaries while another
#: thread peaks, by how much depending on how their work interleaves (the CPUs' load). The insertion
#: target beside a CPU-bound process peaked at 426-455 MB, 396 MB with one heap (docs/decisions.md, "mem:").
HEAP_ARENAS = 1
#: The environment variables that set the thresholds when a process starts (a user's choice
#: wins), each with its ``mallopt`` parameter and the command's value.
HEAP_ENV = {"MALLOC_MMAP_THRESHOLD_": (_M_MMAP_THRESHOLD, HEAP_REUSE_BYTES),
            "MALLOC_TRIM_THRESHOLD_": (_M_TRIM_THRESHOLD, HEAP_TOP_BYTES),
            "MALLOC_ARENA_MAX": (_M_ARENA_MAX, HEAP_ARENAS)}


def heap_environment() -> dict[str, str]:
    """The heap thresholds a process of the command starts with: the environment's, else the command's."""
    return {name: os.environ.get(name, str(value)) for name, (_, value) in HEAP_ENV.items()}


@functools.lru_cache(maxsize=1)
def _mallopt() -> Callable[[int, int], int] | None:
    """glibc's ``mallopt``, or None where the C library has none."""
    return _libc_function("mallopt", [ctypes.c_int, ctypes.c_int])


def reuse_freed_arrays() -> bool:
    """Let the C heap reuse freed arrays (up to :data:`HEAP_REUSE_BYTES`) instead of unmapping each one.

    glibc maps a large block (above a threshold that starts at 128 KiB) on pages of its own
    and unmaps them when it is freed, so the next filter step's arrays of the same size fault
    in fresh zeroed pages: a belief step over a batch of 384 episodes allocates its weights and
    particles anew (3-6 MB each) and spent 1-7 us per episode-step in page faults here, depending
    on what ran before (``benchmarks/belief.py``). Raising the mapping threshold keeps such
    blocks in the heap, and the trimming threshold up to :data:`HEAP_TOP_BYTES` of free memory at
    its top; the explicit :func:`trim_heap` between chunks and :func:`release_free_heap` between
    phases still return the memory. The ``probecommit`` command calls this at start;
    a program importing probecommit keeps its own allocator settings unless it calls it.
    It also keeps every thread on one heap (:data:`HEAP_ARENAS`). A setting in the environment
    (``MALLOC_MMAP_THRESHOLD_``, ``MALLOC_TRIM_THRESHOLD_``, ``MALLOC_ARENA_MAX``) is the user's and
    is left alone; the others are exported so worker processes start with them.

    Returns:
        True when glibc took the setting, False where the C library has no ``mallopt``.
    """
    mallopt = _mallopt()
    if mallopt is None:
        return False
    taken = True
    for name, (parameter, value) in HEAP_ENV.items():
        if name in os.environ:
            continue
        taken &= mallopt(parameter, value) == 1
        os.environ[name] = str(value)
    return taken


#: Within :func:`large_arrays_apart`, blocks above this size get pages of their own.
APART_BYTES = 2 * 1024**2


@contextlib.contextmanager
def large_arrays_apart(threshold: int = APART_BYTES) -> Iterator[bool]:
    """Within the block, an array above ``threshold`` bytes that no free block of the heap can
    hold gets pages of its own (glibc's mmap threshold), handed back when freed, instead of
    growing the heap; while the command's heap setting is in force.

    A loop over chunks frees each chunk's arrays before the next chunk allocates its own (and
    trims the heap), but the small objects a chunk leaves behind (its share of the output,
    answers kept for later passes) sit between the freed blocks, and the next chunk's large
    arrays no longer all fit where the last chunk's were: the heap grew by a few MB over a long
    run's chunks (``benchmarks/memory.py``). It costs page faults (calibrate on 3072 episodes:
    about 15 % longer here), so it is used around loops over several chunks only. A threshold
    other than the command's (a user's ``MALLOC_MMAP_THRESHOLD_``, or a program that never set
    one) is left alone.

    Yields:
        Whether the threshold was changed.
    """
    mallopt = _mallopt()
    ours = os.environ.get("MALLOC_MMAP_THRESHOLD_") == str(HEAP_REUSE_BYTES) and not _in_heap
    changed = mallopt is not None and ours and mallopt(_M_MMAP_THRESHOLD, threshold) == 1
    if changed:
        _apart_thresholds.append(threshold)
    try:
        yield changed
    finally:
        if changed:  # back to the enclosing block's threshold, or the command's
            _apart_thresholds.pop()
            mallopt(_M_MMAP_THRESHOLD, _apart_thresholds[-1] if _apart_thresholds else HEAP_REUSE_BYTES)


#: The thresholds of the :func:`large_arrays_apart` blocks in force, innermost last.
_apart_thresholds: list[int] = []
#: The :func:`large_arrays_in_heap` blocks in force (none: :func:`large_arrays_apart` takes effect).
_in_heap: list[bool] = []


@contextlib.contextmanager
def large_arrays_in_heap() -> Iterator[None]:
    """Within the block, :func:`large_arrays_apart` changes nothing: large arrays stay in the heap,
    where a freed one is reused by the next without faulting in fresh pages.

    Why: since the command keeps one heap per process (:data:`HEAP_ARENAS`), mapping each large
    array apart saves little of a calibration's peak but costs its page faults: ``probecommit
    calibrate`` at E = 12288, 4.6 M faults and 11 s of system time against 2.6 M and 6.5-6.8 s in the
    heap, its peak 513 against 530-532 MB (docs/decisions.md, "cal3:"). A command whose peak matters
    more than its time (a reproduction's targets) keeps the blocks.
    """
    _in_heap.append(True)
    try:
        yield
    finally:
        _in_heap.pop()


def trim_heap() -> bool:
    """Return the C heap's free pages to the system (glibc's ``malloc_trim``; no garbage collection).

    Cheap enough between the chunks of a long loop, so that each chunk's arrays go back
    before the next chunk's are allocated instead of piling up as heap fragments.

    Returns:
        True when the heap was trimmed (glibc), False where the C library cannot.
    """
    trim = _malloc_trim()
    if trim is None:
        return False
    trim(0)
    return True


def release_free_heap() -> bool:
    """Collect garbage and return the C heap's free pages to the system.

    glibc keeps the memory of freed arrays in its heap for reuse; after a phase that
    held a run's beliefs, a long job would carry that retained memory into the next
    phase. Called between the phases of a reproduction, so each phase's peak starts
    from what is live rather than from the last phase's high-water mark.

    Returns:
        True when the heap was trimmed (glibc), False where the C library cannot.
    """
    gc.collect()
    return trim_heap()
