"""Help that shows a flag as a flag.

typer's rich help prints a type column for every option, ``<bool>`` for a flag such
as ``--help`` or ``--fixed-probes``, which reads as if the flag took a value. A flag
(an on/off option, or a counter such as ``-vv``) gets no type column here; every other option keeps
its own. Imported once by :mod:`probecommit.cli.app`.
"""

from __future__ import annotations

from typer.core import TyperOption

_original = TyperOption.display_type_rich


def _display_type_rich(self: TyperOption, ctx):  # type: ignore[no-untyped-def]
    if getattr(self, "is_flag", False) or getattr(self, "count", False):
        return None
    return _original(self, ctx)


if not getattr(TyperOption.display_type_rich, "_probecommit", False):
    _display_type_rich._probecommit = True  # type: ignore[attr-defined]
    TyperOption.display_type_rich = _display_type_rich  # type: ignore[method-assign]
