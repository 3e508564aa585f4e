"""Shared CLI plumbing: the safe consoles, the user-error wrapper, progress bars.

Every text the CLI shows goes through :data:`console` or :data:`err_console`, which never
interpret anything in it: no Rich markup (``[red]``, ``[@click=...]``), no emoji codes
(``:fire:``), no highlighting, and every control character (an ANSI escape from a
directory name included) shown as ``?``. Styling is done with :class:`rich.text.Text`
styles, never with markup in a string, so text from data or paths prints as it is.
"""

from __future__ import annotations

import errno
import functools
import re
from typing import Callable

import typer
from rich.console import Console
from rich.text import Text

from probecommit.errors import UserError

# Errors a user can cause and fix (bad config, bad log, wrong directory, a missing file or
# extra, a full disk): one line, exit 2. Any other exception is a bug: exit 1 (see diagnostics).
USER_ERRORS: tuple[type[BaseException], ...] = (UserError, OSError, ImportError, MemoryError)
#: click's base of usage errors (typer vendors click; found through a class typer exports).
_CLICK_EXCEPTION = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def clean(text: object) -> str:
    """``text`` with every control character (C0, C1, line separators, bidi overrides) as ``?``."""
    return _CONTROL.sub("?", str(text))


class SafeConsole(Console):
    """A console that renders every string literally: no markup, no emoji codes, no highlighting,
    control characters shown as ``?`` (tables' titles and cells included: they render through here)."""

    def __init__(self, **kwargs) -> None:
        super().__init__(markup=False, emoji=False, highlight=False, **kwargs)

    def render_str(self, text: str, **kwargs) -> Text:  # type: ignore[override]
        kwargs.update(markup=False, emoji=False, highlight=False)
        return super().render_str(clean(text), **kwargs)


console = SafeConsole()
err_console = SafeConsole(stderr=True)


def one_line(text: object) -> str:
    """``text`` on one line: newlines and runs of spaces become single spaces."""
    return " ".join(str(text).split())


def safe(text: object) -> str:
    """A string from data or a path, safe to print: control characters (ANSI escape sequences
    included) shown as ``?``. The consoles interpret no markup, so nothing else needs escaping."""
    return clean(text)


def os_error_line(exc: OSError) -> str:
    """One line for an OS error, naming the path and what went wrong (an error of ours with no
    errno, a refused symlink, carries its own message)."""
    if exc.errno is None and exc.args:
        return str(exc)
    what = {errno.ENOSPC: "the disk is full", errno.EROFS: "the file system is read-only",
            errno.EACCES: "permission denied", errno.ENAMETOOLONG: "the name is too long",
            errno.EEXIST: "it already exists", errno.ENOTDIR: "a path component is a file, not a directory",
            errno.EISDIR: "it is a directory"}.get(exc.errno, exc.strerror or type(exc).__name__)
    where = exc.filename or "a file"
    return f"cannot write or read {where}: {what}"


def print_error(exc: BaseException) -> None:
    """One line on stderr, never wrapped at the terminal width."""
    text = os_error_line(exc) if isinstance(exc, OSError) and not isinstance(exc, FileNotFoundError) else (one_line(exc) or type(exc).__name__)
    err_console.print(Text("error:", style="red"), clean(one_line(text)), soft_wrap=True)


def print_warning(message: str) -> None:
    err_console.print(Text("warning:", style="yellow"), clean(one_line(message)), soft_wrap=True)


def user_errors(fn: Callable) -> Callable:
    """Turn user-caused errors into one red line and exit code 2, never a traceback; any other
    exception into one line naming it as a bug, exit code 1 (the traceback with ``--debug``)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except (typer.Exit, typer.Abort, _CLICK_EXCEPTION):  # typer's own: exit, abort, a usage error
            raise
        except KeyboardInterrupt:
            print_warning("interrupted; finished work is kept: rerun the same command to resume")
            raise typer.Exit(130) from None
        except USER_ERRORS as exc:
            from probecommit.cli.diagnostics import debugging

            if debugging():
                import traceback

                err_console.file.write("".join(traceback.format_exception(exc)))
            print_error(exc)
            raise typer.Exit(2) from None
        except Exception as exc:  # noqa: BLE001 - a bug: say so, exit 1
            from probecommit.cli.diagnostics import report_internal_error

            report_internal_error(exc, lambda text: err_console.print(Text("error:", style="red"), safe(one_line(text)),
                                                                      soft_wrap=True))
            raise typer.Exit(1) from None

    return wrapper


def redraws(target) -> bool:
    """Whether a live display on ``target`` shows its redraws (a terminal or a notebook). Elsewhere (a
    pipe, a file, a dumb terminal) rich prints only the final state, when the bar stops, so a refresh
    thread would only rebuild the bar ten times a second for nothing (0.04-0.06 s of CPU in a
    10 s run, ``docs/decisions.md``, spd22)."""
    return bool(target.is_jupyter or (target.is_terminal and not target.is_dumb_terminal))


def progress_bar(description: str):
    """A rich progress bar and a ``(done, total)`` callback that drives it. The command's work begins
    here: its start-up objects are frozen out of the garbage collector's walks (``process/collector.py``)."""
    # Imported here: only the commands that run work draw a bar (``--help`` and the rest start without it).
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from probecommit.process.collector import startup_done

    startup_done()

    bar = Progress(
        TextColumn("{task.description}", style="bold", markup=False), BarColumn(), MofNCompleteColumn(),
        TimeElapsedColumn(), TimeRemainingColumn(), console=err_console, transient=False,
        auto_refresh=redraws(err_console),
    )
    task = bar.add_task(description, total=None)

    def update(done: int, total: int) -> None:
        bar.update(task, completed=done, total=total)

    return bar, update
