"""``probecommit tasks --check NAME``: run :func:`probecommit.check_family` and print what it found."""

from __future__ import annotations

import typer

from probecommit.cli.common import console, print_error
from probecommit.cli.common import safe as escape


def check_command(name: str) -> None:
    """Check family ``name`` in every installed engine; exit 1 listing each failure and its declaration."""
    from probecommit.runner.family_check import check_family
    report = check_family(name, raise_errors=False)  # an unknown name raises a UserError: one line
    for check in report.passed:
        console.print(f"ok   {escape(check)}")
    for check, why in report.skipped:
        console.print(f"skip {escape(check)}: {escape(why)}")
    for line in report.lines():
        print_error(f"FAIL {line}")
    if not report.ok:
        raise typer.Exit(1)
    console.print(f"family {escape(name)!s}: all {len(report.passed)} checks passed")
