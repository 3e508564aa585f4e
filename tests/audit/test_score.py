"""The episode score identity: s <= t implies coverage of the retained set at t (paper Sec. IV).

The exact statement tested is stronger: the retained set at ``t`` covers the truth
if and only if ``s <= W_{m(t)}``, the mass of the prefix it keeps; since
``W_{m(t)} >= t``, ``s <= t`` implies coverage. The one exception is the
zero-weight plateau at ``W = 1``: zero-weight particles sort last, so the prefix
kept at ``t = 1`` stops at the last positive weight, and a truth spanned only by
zero-weight particles has ``s = 1`` without being covered.
"""

import numpy as np
import pytest

from probecommit.audit.score import coverage_score
from probecommit.core.retained import masked_interval, prefix_mass, retained_count, retained_mask

D = 20.0


def random_beliefs(rng, e=400, n=40, ties=True, zeros=True):
    z = rng.uniform(-10, 10, (e, n))
    if ties:
        # Quantized weights give many exact ties; some rows are fully uniform (after resampling).
        w = rng.integers(1, 5, (e, n)).astype(float)
        w[: e // 8] = 1.0
    else:
        w = rng.exponential(1.0, (e, n))
    if zeros:
        w[rng.random((e, n)) < 0.15] = 0.0
        w[:, 0] = np.maximum(w[:, 0], 1.0)  # at least one positive weight
    w /= w.sum(axis=1, keepdims=True)
    # Truths: inside the hull mostly, some outside, some exactly on particles.
    z_true = rng.uniform(-12, 12, e)
    on = rng.random(e) < 0.2
    z_true[on] = z[on, rng.integers(0, n, on.sum())][np.arange(on.sum())] if on.any() else z_true[on]
    return z, w, z_true


@pytest.mark.parametrize("ties,zeros", [(True, True), (False, False), (True, False), (False, True)])
def test_score_at_most_t_implies_coverage(ties, zeros):
    rng = np.random.default_rng(10 + 2 * ties + zeros)
    z, w, z_true = random_beliefs(rng, ties=ties, zeros=zeros)
    s = coverage_score(z, w, z_true, D)
    for t in np.r_[rng.uniform(0.01, 0.999, 25), [0.5, 0.8, 0.25]]:
        lo, hi = masked_interval(z, retained_mask(w, t))
        covered = (lo <= z_true) & (z_true <= hi)
        assert np.all(covered[s <= t]), t
        # Exact form: covered iff s <= W_{m(t)}, the mass actually kept.
        _, cum = prefix_mass(w)
        kept_mass = np.take_along_axis(cum, (retained_count(w, t) - 1)[:, None], axis=1)[:, 0]
        np.testing.assert_array_equal(covered, s <= kept_mass)


def test_score_is_a_mass_inside_the_hull_and_continues_past_one_outside():
    rng = np.random.default_rng(3)
    z, w, z_true = random_beliefs(rng, e=2000)
    s = coverage_score(z, w, z_true, D)
    hull_lo, hull_hi = z.min(axis=1), z.max(axis=1)
    escaped = (z_true < hull_lo) | (z_true > hull_hi)
    assert escaped.any() and (~escaped).any()
    np.testing.assert_array_equal(s > 1, escaped)
    assert np.all(s[~escaped] > 0) and np.all(s[~escaped] <= 1.0)
    distance = np.where(z_true < hull_lo, hull_lo - z_true, z_true - hull_hi)
    np.testing.assert_allclose(s[escaped], 1 + distance[escaped] / D, rtol=0, atol=1e-12)


def test_score_never_exceeds_one_inside_hull_despite_round_off():
    # Normalized weights whose float cumulative sum overshoots 1 by one ulp.
    w = np.array([[0.446969696969697, 0.2954545454545455, 0.2575757575757576]])
    assert np.cumsum(w)[-1] > 1.0
    z = np.array([[0.0, 1.0, 5.0]])
    s = coverage_score(z, w, np.array([4.0]), D)
    assert s[0] == 1.0


def test_zero_weight_plateau_is_the_documented_exception():
    # Positive weights on particles at 0 and 1; the truth (3.0) is spanned only once the
    # zero-weight particle at 5.0 joins, so s = W = 1 but the t = 1 set stops before it.
    z = np.array([[0.0, 1.0, 5.0]])
    w = np.array([[0.5, 0.5, 0.0]])
    s = coverage_score(z, w, np.array([3.0]), D)
    assert s[0] == pytest.approx(1.0)
    lo, hi = masked_interval(z, retained_mask(w, 1.0))
    assert (lo[0], hi[0]) == (0.0, 1.0)  # not covered: the plateau exception


@pytest.mark.parametrize("zeros", [False, True])
def test_at_t_equal_one_only_the_plateau_breaks_the_implication(zeros):
    rng = np.random.default_rng(7)
    z, w, z_true = random_beliefs(rng, e=3000, zeros=zeros)
    s = coverage_score(z, w, z_true, D)
    lo, hi = masked_interval(z, retained_mask(w, 1.0))
    broken = (s <= 1.0) & ~((lo <= z_true) & (z_true <= hi))
    pos_lo = np.where(w > 0, z, np.inf).min(axis=1)
    pos_hi = np.where(w > 0, z, -np.inf).max(axis=1)
    plateau = (z_true < pos_lo) | (z_true > pos_hi)  # spanned only with zero-weight particles
    if not zeros:
        assert not broken.any()
    else:
        assert broken.any()  # the exception does occur with dead particles
        assert np.all(plateau[broken])
