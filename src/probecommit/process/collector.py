"""The cyclic garbage collector while the ``probecommit`` command starts.

A command's start-up (its imports: NumPy, pandas, pyarrow, pydantic and the families' configs,
an engine) builds about a hundred thousand tracked objects that live as long as the process. At
CPython's default thresholds (700, 10, 10) the collector walked them over and over while they
were built (about 260 young, 24 middle and 2 full collections in a 96 x 4 MuJoCo run), and every
later full collection walked them again: 0.14 s of CPU in that run (measured with
``gc.callbacks``), about a tenth of what the run spends beyond its engine queries. None of it
finds garbage worth the walk: what start-up builds stays.

So the command collects young objects only every :data:`STARTUP_THRESHOLD` allocations while it
starts (:func:`defer_collection`) and, once its work begins (:func:`startup_done`, when it draws
its progress bar), collects the youngest generation, freezes what is left (``gc.freeze``: never
walked again) and restores the thresholds. The middle generation's garbage is frozen with the
rest rather than walked for (10 objects in that run, against 0.03-0.04 s to collect them; a full
collection there finds no older garbage). A command that draws no bar keeps the start-up
threshold to its end: the collector still runs, every 50,000 allocations instead of 700.
Nothing here changes a result: only when unreachable cycles are freed. A program that imports
probecommit keeps its own collector settings (only the command's ``main()`` calls this).
"""

from __future__ import annotations

import gc

#: Net allocations of container objects between two young collections while the command starts
#: (CPython's default is 700). Middle and full collections follow at the usual ratios, so at this
#: threshold start-up runs none of the full ones.
STARTUP_THRESHOLD = 50_000

#: The thresholds :func:`defer_collection` replaced, while start-up lasts; None otherwise.
_saved: tuple[int, int, int] | None = None


def defer_collection() -> None:
    """Collect young objects every :data:`STARTUP_THRESHOLD` allocations until :func:`startup_done`
    (a no-op when already deferred, or when the collector is disabled)."""
    global _saved
    if _saved is not None or not gc.isenabled():
        return
    _saved = gc.get_threshold()
    gc.set_threshold(STARTUP_THRESHOLD, *_saved[1:])


def startup_done() -> bool:
    """Start-up is over: free the youngest generation's unreachable cycles, freeze the objects left
    (``gc.freeze``, so later collections do not walk them) and restore the thresholds.

    Returns:
        True when start-up was deferred (and so is now ended), False when there was nothing to do.
    """
    global _saved
    if _saved is None:
        return False
    saved, _saved = _saved, None
    gc.collect(0)  # the young garbage (70 objects in that run) is freed, not frozen with what stays
    gc.freeze()
    gc.set_threshold(*saved)
    return True
