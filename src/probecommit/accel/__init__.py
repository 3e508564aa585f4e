"""The compiled production path: numba JIT kernels (on-disk cache) for the hot loops of ``core``.

``probecommit.core`` is the reference implementation, in plain NumPy, readable against the
paper's equations; it never imports this package. The runner injects what is here into the
core's objects (``ParticleFilter(kernels=...)``, ``ProbeRobust(kernels=...)``) through
:func:`production`. The kernels agree with the NumPy reference to a stated tolerance
(``tests/accel``), not bit for bit: they sum in their own order. Counts, sorts, cumulative sums
and the seed hash are exact, so retained sets, coverage scores and random streams agree exactly
wherever the weights do.

One module per caller: :mod:`.belief` (the filter's update), :mod:`.retained` (retained sets,
coverage score, posterior variance), :mod:`.executors` (the scenario counts), :mod:`.seeding`
(the episodes' random streams); :mod:`.compiled` says how they run (a module built ahead of
time from the same source when current, else numba's JIT with its on-disk cache). The runner
imports them only when it computes: ``probecommit --help`` never loads them.

``PROBECOMMIT_KERNELS=numpy`` runs the NumPy reference instead (a process-wide choice, so a run
is computed by one path throughout); ``numba`` (the default) the kernels.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Any, Callable

#: The two paths: the compiled kernels, or the core's NumPy reference.
MODES = ("numba", "numpy")


def mode() -> str:
    """The path this process computes with (``PROBECOMMIT_KERNELS``: ``numpy``, else ``numba``;
    ``aot`` or ``jit`` pick how the kernels are loaded, :mod:`.compiled`)."""
    choice = os.environ.get("PROBECOMMIT_KERNELS", "").strip().lower() or "numba"
    if choice in ("aot", "jit"):
        return "numba"
    if choice not in MODES:
        raise ValueError(f"PROBECOMMIT_KERNELS={choice!r}: expected one of {', '.join(MODES)}, aot or jit")
    return choice


@dataclass(frozen=True)
class Kernels:
    """What the runner injects: one bundle per caller, and the two belief summaries a commit takes."""

    filter: Any  # core.belief.FilterKernels
    sets: Any  # core.executors.SetKernels
    coverage_with_hull: Callable[..., Any]
    weighted_variance: Callable[..., Any]
    #: ``(entropy[K, L] uint64, n_words) -> [K, n_words] uint32``, or None (NumPy's SeedSequence).
    seed_words: Callable[..., Any] | None


def production(choice: str | None = None) -> Kernels:
    """The kernels of ``choice`` (default :func:`mode`): compiled, or the core's NumPy reference."""
    return _kernels(mode() if choice is None else choice)


@functools.lru_cache(maxsize=None)
def _kernels(choice: str) -> Kernels:
    if choice == "numpy":
        from probecommit.core.belief import FilterKernels
        from probecommit.core.executors import SetKernels
        from probecommit.core.retained import coverage_with_hull, weighted_variance

        return Kernels(FilterKernels(), SetKernels(), coverage_with_hull, weighted_variance, None)
    from probecommit.accel import belief, executors, retained, seeding

    return Kernels(belief.KERNELS, executors.KERNELS, retained.coverage_with_hull, retained.weighted_variance,
                   seeding.seed_sequence_words)
