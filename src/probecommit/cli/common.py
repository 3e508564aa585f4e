"""Shared CLI plumbing: consoles, the user-error wrapper, progress bars."""

from __future__ import annotations

import functools
from typing import Callable

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

console = Console()
err_console = Console(stderr=True)

# Errors a user can cause (bad config, bad log, wrong directory): one line, exit 2.
USER_ERRORS: tuple[type[BaseException], ...] = (ValueError, FileNotFoundError, RuntimeError, ImportError)


def one_line(text: object) -> str:
    """``text`` on one line: newlines and runs of spaces become single spaces."""
    return " ".join(str(text).split())


def print_error(exc: BaseException) -> None:
    """One line on stderr, never wrapped at the terminal width."""
    err_console.print(f"[red]error:[/red] {escape(one_line(exc) or type(exc).__name__)}", soft_wrap=True, highlight=False)


def print_warning(message: str) -> None:
    err_console.print(f"[yellow]warning:[/yellow] {escape(one_line(message))}", soft_wrap=True, highlight=False)


def user_errors(fn: Callable) -> Callable:
    """Turn user-caused errors into one red line and exit code 2, never a traceback."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except typer.Exit:
            raise
        except USER_ERRORS as exc:
            print_error(exc)
            raise typer.Exit(2) from None

    return wrapper


def progress_bar(description: str):
    """A rich progress bar and a ``(done, total)`` callback that drives it."""
    bar = Progress(
        TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
        TimeElapsedColumn(), TimeRemainingColumn(), console=err_console, transient=False,
    )
    task = bar.add_task(description, total=None)

    def update(done: int, total: int) -> None:
        bar.update(task, completed=done, total=total)

    return bar, update
