"""Memory estimates before large allocations (refuse with the number and the setting to
change), and handing freed heap memory back to the system between long phases."""

from __future__ import annotations

import ctypes
import functools
import gc
import os
from typing import Callable

#: Share of the available memory one allocation may take.
SHARE = 0.5


def available_bytes() -> int:
    """Memory available to this process now (``MemAvailable``; 8 GiB when it cannot be read)."""
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


def check_fits(needed_bytes: float, what: str, setting: str) -> None:
    """Raise ``MemoryError`` with one line when ``needed_bytes`` exceeds half the available memory.

    Args:
        needed_bytes: The estimate.
        what: What would be allocated ("the particle beliefs of one work unit").
        setting: What to change ("belief.particles or unit_instances").
    """
    limit = SHARE * available_bytes()
    if needed_bytes > limit:
        raise MemoryError(f"{what} would need about {needed_bytes / 1024**3:.1f} GiB, more than half the "
                          f"{available_bytes() / 1024**3:.1f} GiB available; reduce {setting}")


@functools.lru_cache(maxsize=1)
def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, or None where the C library has none (macOS, musl)."""
    try:
        trim = ctypes.CDLL(None).malloc_trim  # the symbols already loaded: no library search
    except (OSError, AttributeError):
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


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
