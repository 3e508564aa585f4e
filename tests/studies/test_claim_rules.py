"""Each comparison rule is as strict as the paper's sentence (issue 36, decisions.md "ruleB").

Why: a rule looser than the claim lets a difference pass as "reproduced". Each test gives a
hand value the old, looser rule passed and the new rule fails, and one that the new rule passes.
"""

from __future__ import annotations

from probecommit.studies import claims as C
from probecommit.studies import paper_values as P
from tests.studies.test_claims import _lookup


def _claim(cid):
    return next(c for c in C.CLAIMS if c.id == cid)


def _comparison(cid, label):
    return next(c for c in _claim(cid).comparisons if c.label == label)


def _pool(ec, nc, er, nr, gate="adjusted"):
    g = f"{C.I}gates.summary.{C.GATES[gate]}."
    return _lookup({f"{g}escaped_committed": ec, f"{g}n_committed": nc, f"{g}escaped_rejected": er,
                    f"{g}n_rejected": nr})


def test_t33_tests_the_ratio_not_above():
    rule = _comparison("T33-committed-pool", "adjusted")
    assert 42 / 230 > 18 / 154  # the old rule ("above") passed this: ratio 1.56
    assert not rule.test(_pool(42, 230, 18, 154))
    assert rule.test(_pool(41, 231, 9, 153))  # the paper's own adjusted gate, ratio 3.0
    assert rule.test(_pool(1, 100, 0, 100))  # no rejected escape: any committed escape is many times it
    assert not rule.test(_pool(0, 100, 0, 100))  # no escape at all is no multiple
    assert {c.label for c in _claim("T33-committed-pool").comparisons} == {"raw", "adjusted", "posterior_variance"}


def _prior(coverage, escape, optimism):
    r = f"{C.R}prior_by_mm.12."
    return _lookup({f"{r}coverage": coverage, f"{r}escape": escape, f"{r}optimism": optimism})


def test_t29_compares_each_of_the_papers_three_numbers():
    claim = _claim("T29-replay-prior")
    ours = _prior(0.25, 0.75, 0.525)  # both conditions fire: the old two Holds passed it
    assert [c.label for c in claim.comparisons if not c.test(ours)] == [
        "coverage at +-12 mm", "escape at +-12 mm", "optimism at +-12 mm"]
    assert all(c.test(_prior(0.63, 0.37, 0.27)) for c in claim.comparisons)
    assert C.evaluate(claim, ours, lambda p: True).status == "differs, unexplained"


def _signatures(escape_at):
    """Fig. 7's points: escape 0 but where ``escape_at`` says, the boundary fault's rising with k."""
    sig = f"{C.I}fault_signatures."
    rising = {("boundary", k): k / 100 for k in C.SIGNATURE_BUDGETS}
    return _lookup({f"{sig}{fault}.{k}.{m}": {**rising, **escape_at}.get((fault, k), 0.0) if m == "escape" else float(k)
                    for fault in C.FAULT_ROWS for k in C.SIGNATURE_BUDGETS for m in ("escape", "optimism")})


def test_fig_signatures_bounds_escape_at_every_budget_for_frame_and_the_noise_line():
    claim = _claim("fig:signatures")
    two = 2 / P.value("fig:signatures.n")
    assert C.evaluate(claim, _signatures({}), lambda p: True).status == "reproduced"
    # The old rule read frame at k = 8 only: two escapes at k = 3 passed it.
    assert C.evaluate(claim, _signatures({("frame", 3): two}), lambda p: True).failed == ["frame k=3"]
    assert C.evaluate(claim, _signatures({("noise", 1): two}), lambda p: True).failed == ["noise k=1"]


def test_tab_testc_compares_every_printed_number():
    labels = {c.label for c in _claim("tab:testc").comparisons}
    for row in C.TESTC_ROWS:
        assert {f"{row} old", f"{row} corrected", f"{row} old - corrected"} <= labels
    assert {"set+margin old", "set+margin corrected", "set+margin old - corrected"} <= labels
    printed = {k.rsplit(".", 1)[0] for k in P.PRINTED if k.startswith("tab:testc.")}
    assert len(printed) == len(C.TESTC_ROWS) + 1
    # Escape corrected: the old registry did not compare it; a corrected escape interval off zero now fails.
    rule = _comparison("tab:testc", "escape_random_k8 corrected")
    key = f"{C.I}table_testc.escape_random_k8.corrected"
    assert rule.test(_lookup({key: [0.0, 0.0, 0.0]}))
    assert not rule.test(_lookup({key: [0.05, 0.02, 0.08]}))


def _taps(optimism, lo, hi):
    return _lookup({k: v for t in range(5) for k, v in (
        (f"{C.R}table.{t}.optimism", optimism), (f"{C.R}table.{t}.optimism_lo", lo),
        (f"{C.R}table.{t}.optimism_hi", hi))})


def test_t26_bounds_optimism_within_the_papers_distance_of_zero_at_each_tap_count():
    claim = _claim("T26-hardware-optimism")
    wide = _taps(0.198, -0.05, 0.45)  # the interval covers zero (the old rule's only test); optimism beyond 0.12
    assert C.evaluate(claim, wide, lambda p: True).failed == [f"{t} taps within bound" for t in range(1, 6)]
    assert C.evaluate(claim, _taps(0.05, -0.05, 0.15), lambda p: True).status == "reproduced"


def test_the_simulated_rig_counts_are_the_registry_flags():
    rig = [c for c in C.CLAIMS if c.simulated_rig and not c.physical]
    outcomes = {c.id: C.Outcome("reproduced", 1, 1) for c in C.CLAIMS}
    outcomes[rig[0].id] = C.Outcome("differs, unexplained", 0, 1)
    counts = C.counts_simulated_rig(outcomes)
    assert counts["reproduced"] == len(rig) - 1 and counts["differs, unexplained"] == 1
    assert counts["total"] == len(rig) and counts["missing"] == 0
    hardware = _claim("tab:hardware")  # physical: missing for the arm, not decided by the rig
    assert hardware.simulated_rig and hardware.physical and hardware not in rig
