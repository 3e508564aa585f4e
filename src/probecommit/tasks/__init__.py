"""Task families: one folder each with an analytic ``model.py`` and engine simulators."""
