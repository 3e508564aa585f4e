"""The one decorator every kernel uses: numba's nopython JIT, cached on disk, GIL released.

The first call of a kernel compiles it for its argument types (seconds) and writes the
machine code beside the source (``__pycache__``); later processes load it from there.
``nogil`` lets the runner's threads use several cores.
"""

from __future__ import annotations

from typing import Any, Callable

import numba


def kernel(func: Callable[..., Any]) -> Any:
    """A kernel entry point (called from Python)."""
    return numba.njit(cache=True, nogil=True)(func)


def helper(func: Callable[..., Any]) -> Any:
    """A function only kernels call, inlined into them."""
    return numba.njit(cache=True, nogil=True, inline="always")(func)
