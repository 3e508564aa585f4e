"""The range check's rule for which keys are rates (``report.checks._is_rate``).

A count named by its outcome (``held_failures``, ``n_escaped``) must never be range-checked as a
rate, and a rate must stay one whatever prefix a helper gives it: both generated here.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.report.checks import COUNT_ENDINGS, COUNT_PREFIXES, RATE_WORDS, _is_rate

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


@settings(max_examples=100, deadline=None)
@given(PREFIX, st.sampled_from(COUNT_PREFIXES), st.sampled_from(RATE_WORDS), st.sampled_from(("", "_at_least.3", "_is_beyond")))
def test_a_key_starting_with_what_it_counts_is_a_count(prefix, counted, word, tail):
    """``sessions_failing_at_least.3`` and ``positions_escape_is_beyond`` count sessions and positions."""
    assert not _is_rate(f"{prefix}{counted}{word}{tail}")


def test_counted_units_hand_cases():
    assert not _is_rate("ex36_testc.passes.failing_count")
    assert not _is_rate("rig_redraws.optimism.sessions_failing_at_least.3")
    assert not _is_rate("prior_by_position.12.positions_escape_is_beyond")
    assert _is_rate("prior_by_position.12.share_escape")
