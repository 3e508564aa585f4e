"""Adapters that make a family from what a user already has: plain functions
(:mod:`~probecommit.tasks.adapters.functions`) or a Gymnasium environment
(:mod:`~probecommit.tasks.adapters.gym`). Not a family itself: importing it registers nothing."""
