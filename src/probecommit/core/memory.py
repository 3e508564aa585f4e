"""Memory estimates before large allocations: refuse with the number and the setting to change."""

from __future__ import annotations

import os

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
