"""probecommit: probe a few times, commit once, audit offline."""

__version__ = "0.1.0"
