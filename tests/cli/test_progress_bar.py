"""The progress bar redraws only where a redraw is seen, and prints the same final line elsewhere."""

from __future__ import annotations

import io

from rich.console import Console

from probecommit.cli.common import progress_bar, redraws


def test_redraws_only_on_a_terminal_or_a_notebook(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    assert not redraws(Console(file=io.StringIO()))  # a pipe or a file
    assert redraws(Console(file=io.StringIO(), force_terminal=True))
    assert redraws(Console(file=io.StringIO(), force_jupyter=True))
    monkeypatch.setenv("TERM", "dumb")
    assert not redraws(Console(file=io.StringIO(), force_terminal=True))


def test_a_bar_in_a_pipe_runs_no_refresh_thread_and_prints_its_final_state(monkeypatch):
    out = io.StringIO()
    monkeypatch.setattr("probecommit.cli.common.err_console", Console(file=out, width=80))
    bar, update = progress_bar("units")
    assert not bar.live.auto_refresh
    with bar:
        assert bar.live._refresh_thread is None  # noqa: SLF001 - what auto_refresh=False means
        update(1, 3)
        update(3, 3)
    assert out.getvalue().count("\n") == 1 and "units" in out.getvalue() and "3/3" in out.getvalue()
