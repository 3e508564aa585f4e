"""E222's split of the narrowed prior's replay by block position (``studies.robot.prior_by_position``): hand cases."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims as C
from probecommit.studies.robot import prior_by_position


def _rows(spec: list[tuple[str, float, list[tuple[float, float, bool]]]]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``(position, z, [(predicted, realized, escaped), ...])`` -> the sweep's rows at 12 mm and the session's."""
    sweep, session = [], []
    for pid, z, episodes in spec:
        session.append({"instance_id": pid, "z_true": z})
        sweep += [{"instance_id": pid, "fault": "prior", "size": 12.0, "predicted": p, "realized": r, "escaped": e}
                  for p, r, e in episodes]
    sweep.append({"instance_id": "a", "fault": "prior", "size": 8.0, "predicted": 0.0, "realized": 1.0, "escaped": True})
    return pd.DataFrame(sweep), pd.DataFrame(session)


def test_two_positions_one_beyond_give_each_strata_and_the_mixture():
    sweep, session = _rows([("a", -15.0, [(0.2, 1.0, True), (0.4, 1.0, True)]),
                            ("b", 3.0, [(0.5, 0.0, False), (0.1, 0.0, False)])])
    got = prior_by_position(sweep, session, 12.0, share=0.25)
    assert got["positions"] == 2 and got["share_beyond"] == 0.5 and got["positions_escape_is_beyond"] == 2
    assert got["optimism_beyond"] == pytest.approx(0.7) and got["optimism_inside"] == pytest.approx(-0.3)
    assert got["optimism_at_share"] == pytest.approx(0.25 * 0.7 + 0.75 * -0.3)


def test_a_position_inside_that_escapes_breaks_the_mechanism():
    sweep, session = _rows([("a", -15.0, [(0.2, 1.0, True)]), ("b", 3.0, [(0.5, 0.0, True)])])
    assert prior_by_position(sweep, session, 12.0)["positions_escape_is_beyond"] == 1


def test_e222_needs_the_mechanism_and_the_papers_optimism_at_its_share():
    rule = C.EXPERIMENTS["E222"].supports
    paper = C.paper_values.value("T29-replay-prior.optimism")
    assert rule({"m": 12, "n": 12, "o": paper + 0.04}) and not rule({"m": 11, "n": 12, "o": paper})
    assert not rule({"m": 12, "n": 12, "o": paper + 0.06})


def test_e223_counts_a_session_only_if_the_papers_whole_sentence_holds_on_it():
    """Two sessions of one position-budget each: one whose interval covers zero inside the bound, one whose
    optimism is outside the bound though its interval covers zero: half the sessions give the paper's sentence."""
    from probecommit.studies.explain.rig import optimism_summary

    bound = C.paper_values.value("T26-hardware-optimism.bound")
    rows = []
    for session, realized in ((1, [0.0, 1.0] * 4), (2, [1.0, 1.0, 1.0, 0.0] * 2)):
        rows += [{"session": session, "instance_id": f"p{i % 4}", "k": 1, "predicted": 0.5, "realized": r,
                  "covered": True, "escaped": False, "entered": 1.0 - r, "aim_error": 1.0} for i, r in enumerate(realized)]
    out, table = optimism_summary(pd.DataFrame(rows), {"resamples": 200, "seed": 0})
    assert abs(table.loc[table["session"] == 2, "optimism"].iloc[0]) > bound  # 0.75 - 0.5
    assert out["share_sessions_paper_outcome"] == 0.5


def _e223(p: float, w: float, failed: int, sessions_as_many: int, n: int = 30) -> dict:
    """E223's keys: our session fails ``failed`` labels (intervals excluding zero first, then bounds), and
    ``sessions_as_many`` of ``n`` redrawn sessions fail at least as many."""
    v = {"p": p, "w": w, "n": n, **{f"ge{j}": (n if j == 0 else sessions_as_many if j <= failed else 0) for j in range(11)}}
    for t in range(1, 6):
        bad = t <= failed
        v[f"o{t}"], v[f"l{t}"], v[f"h{t}"] = (0.0, 0.01, 0.02) if bad else (0.0, -0.1, 0.1)
    return v


def test_e223_needs_both_sides_a_share_of_sessions_like_the_papers_and_ours_a_draw_of_the_design():
    rule = C.EXPERIMENTS["E223"].supports
    assert C._rig_session_rank(_e223(0.4, 0.05, 3, 7))[:2] == (3, 7)
    assert rule(_e223(0.4, 0.05, 3, 7)) and not rule(_e223(0.0, 0.05, 3, 7)) and not rule(_e223(0.4, 0.2, 3, 7))
    assert not rule(_e223(0.4, 0.05, 5, 0))  # (0 + 1) / 31 < 0.05: ours is not a session the design gives


def test_e225_keys_come_from_the_central_sessions_under_their_own_prefix():
    from probecommit.studies.explain.rig import keys

    rows = [{"session": 1, "instance_id": f"p{i}", "k": 1, "predicted": 0.5, "realized": float(i % 2), "covered": True,
             "escaped": False, "entered": 1.0, "aim_error": 1.0} for i in range(4)]
    boundary = pd.DataFrame({"session": [1], "first_resolved_mm": [float("nan")], "holds_to_mm": [14.0],
                             "sweep_end_mm": [14.0]})
    central = pd.DataFrame(rows).assign(realized=1.0)  # optimism +0.5: beyond the bound
    got = keys(pd.DataFrame(rows), boundary, {"resamples": 200, "seed": 0}, {"central": central})
    assert got["optimism.share_sessions_paper_outcome"] == 1.0 and got["central.optimism.share_sessions_paper_outcome"] == 0.0
    assert got["central.optimism.sessions_failing_at_least.1"] == 1
    assert "central.optimism.sessions" in got and not any(k.startswith("central.") for k in keys(pd.DataFrame(rows), boundary, {"resamples": 200, "seed": 0}))
