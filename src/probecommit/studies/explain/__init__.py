"""Measurements that explain each difference between our reproduction and the paper (``reproduce explain``)."""

from probecommit.studies.explain.study import reproduce_explain

__all__ = ["reproduce_explain"]
