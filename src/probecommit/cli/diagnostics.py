"""What the command line says about itself: ``--version``, ``-v``/``--debug`` logging, internal errors.

A user error (:class:`probecommit.errors.UserError`, a missing file, a full disk) is one
line and exit code 2 (:func:`probecommit.cli.common.user_errors`). Anything else is a bug
in probecommit: :func:`report_internal_error` says so in one line, exit code 1, and with
``--debug`` (or ``PROBECOMMIT_DEBUG=1``) prints the traceback and where to report it.
"""

from __future__ import annotations

import logging
import os
import sys
import traceback

#: The package's root logger: every module logs under it (``probecommit.runner.study``, ...).
LOGGER = "probecommit"
DEBUG_ENV = "PROBECOMMIT_DEBUG"

_state = {"debug": False}


def debugging() -> bool:
    """Whether ``--debug`` (or ``PROBECOMMIT_DEBUG=1``) is on."""
    return _state["debug"] or os.environ.get(DEBUG_ENV, "") not in ("", "0")


class _StderrHandler(logging.StreamHandler):
    """A handler that writes to whatever ``sys.stderr`` is when a record comes (a test runner or a
    notebook may swap it), never to a stream captured once and closed since."""

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:  # StreamHandler.__init__ sets it; the property wins
        pass


def configure_logging(verbose: int = 0, debug: bool = False) -> None:
    """Send the ``probecommit`` logger to stderr: warnings by default, INFO with ``-v``, DEBUG with
    ``-vv`` or ``--debug``. Only the command line does this; a library user keeps the package's
    ``NullHandler`` and routes the ``probecommit`` logger wherever they like."""
    _state["debug"] = bool(debug)
    level = logging.DEBUG if debug or verbose >= 2 else logging.INFO if verbose == 1 else logging.WARNING
    logger = logging.getLogger(LOGGER)
    for handler in list(logger.handlers):
        if getattr(handler, "_probecommit_cli", False):
            logger.removeHandler(handler)
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    handler._probecommit_cli = True  # type: ignore[attr-defined]
    logger.addHandler(handler)
    logger.setLevel(level)


def version_text() -> str:
    """``probecommit --version``: the package version, the code's identity and the engines found."""
    from probecommit import __version__
    from probecommit.store.rundir import code_identity, engine_versions, git_commit, git_dirty

    commit = git_commit()
    if commit:
        identity = f"git {commit[:12]}{' (uncommitted changes)' if git_dirty() else ''}"
    else:
        identity = f"package source sha256 {code_identity()[:12]}"
    versions = engine_versions()
    engines = ", ".join(f"{name} {versions[name]}" if versions.get(name) else f"{name} (not installed)"
                        for name in ("mujoco", "pybullet", "sapien", "ray", "numba"))
    return "\n".join([
        f"probecommit {__version__}",
        f"code: {identity}",
        f"python {versions['python']}; numpy {versions.get('numpy')}; pandas {versions.get('pandas')}",
        f"engines: {engines}",
    ])


def report_internal_error(exc: BaseException, print_line) -> None:
    """An unexpected exception: one line (type and message), then either the traceback and where
    to report it (``--debug``) or how to see it."""
    from probecommit.errors import report_to

    name = type(exc).__name__
    print_line(f"internal error ({name}): {exc}")
    if debugging():
        sys.stderr.write("".join(traceback.format_exception(exc)))
        sys.stderr.write(f"This is a bug in probecommit. Please report it to {report_to()} with the command you ran, "
                         "the output of 'probecommit --version' and the traceback above.\n")
    else:
        sys.stderr.write("This is a bug in probecommit, not in your input: rerun with --debug for the traceback "
                         "and where to report it.\n")
