"""The range check's rule for which keys are rates (``report.checks._is_rate``).

A count named by its outcome (``held_failures``, ``n_escaped``) must never be range-checked as a
rate, and a rate must stay one whatever prefix a helper gives it: both generated here.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.report.checks import COUNT_ENDINGS, RATE_WORDS, _is_rate

PREFIX = st.from_regex(r"[a-z]{1,8}(\.[a-z0-9]{1,6}){0,3}\.", fullmatch=True)
STEM = st.from_regex(r"([a-z]{1,6}_)?", fullmatch=True)


@settings(max_examples=100, deadline=None)
@given(PREFIX, STEM, st.sampled_from(COUNT_ENDINGS))
def test_a_plural_outcome_is_a_count(prefix, stem, ending):
    assert not _is_rate(f"{prefix}{stem}{ending}")


@settings(max_examples=100, deadline=None)
@given(PREFIX, st.sampled_from(("failure", "coverage", "escape", "success", "failure_rate", "realized")))
def test_a_rate_stays_a_rate_whatever_its_prefix(prefix, word):
    assert word.startswith(RATE_WORDS) or word in RATE_WORDS
    assert _is_rate(f"{prefix}{word}")
    assert _is_rate(f"{prefix}{word}.3")  # a list element is read by its parent key


def test_hand_cases():
    assert not _is_rate("ex8_grasp.c4.held_failures")
    assert not _is_rate("cover.n_escaped")
    assert _is_rate("table.deployed.support_escape")
    assert not _is_rate("table.deployed.optimism")
