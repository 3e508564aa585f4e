"""The exception a user can cause and fix, as distinct from a bug in probecommit.

Every error class for bad input (a config, an episode table, a session log, a run
directory, a missing engine) derives from :class:`UserError` as well as from the
built-in class it always was (``ValueError``, ``RuntimeError``, ...), so existing
``except ValueError`` code keeps working. The command line prints a ``UserError`` as
one line with exit code 2; any other exception is an internal error: one line that
says so, exit code 1, and the traceback with ``--debug``.

This module imports nothing, so every layer may use it.
"""


class UserError(Exception):
    """Bad input the user can fix: the message says what and where, on one line."""


def report_to() -> str:
    """Where to report an internal error: the package's ``Issues`` (or ``Bug Tracker``) project URL
    when its metadata has one, else the maintainers named in the package metadata."""
    from importlib import metadata

    try:
        meta = metadata.metadata("probecommit")
    except metadata.PackageNotFoundError:
        return "the probecommit maintainers"
    for entry in meta.get_all("Project-URL") or []:
        label, _, url = entry.partition(",")
        if label.strip().lower() in ("issues", "bug tracker", "tracker"):
            return url.strip()
    return meta.get("Author-email") or meta.get("Author") or "the probecommit maintainers"


class UsageError(UserError, ValueError):
    """A command's options or arguments do not fit together (the message names them)."""


class UnavailableError(UserError, RuntimeError):
    """Something the command needs is not there or not reachable (a Ray cluster's address)."""
