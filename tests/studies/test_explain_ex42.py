"""ex42 (E230, E231): the rig's redraws with the tap, particle and misread streams redrawn; hand cases."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims as C


def _keys(p: float, w: float, failed: int, as_many: int, n: int = 30) -> dict:
    """E230's/E231's keys: our session fails ``failed`` labels (intervals excluding zero first, then bounds) and
    ``as_many`` of ``n`` sessions fail at least as many."""
    v = {"p": p, "w": w, "n": n, **{f"ge{j}": (n if j == 0 else as_many if j <= failed else 0) for j in range(11)}}
    for t in range(1, 6):
        v[f"o{t}"], v[f"l{t}"], v[f"h{t}"] = (0.0, 0.01, 0.02) if t <= failed else (0.0, -0.1, 0.1)
    return v


def test_e230_needs_the_papers_side_and_ours_a_draw_of_the_whole_design():
    rule = C.EXPERIMENTS["E230"].supports
    assert rule(_keys(0.4, 0.05, 5, 1))  # (1 + 1) / 31 = 0.065: one session as extreme as ours is enough
    assert not rule(_keys(0.4, 0.05, 5, 0))  # (0 + 1) / 31 = 0.032
    assert not rule(_keys(0.04, 0.05, 5, 3)) and not rule(_keys(0.4, 0.13, 5, 3))  # the paper's side


def test_e231_reads_only_our_rank_among_sessions_with_our_positions():
    rule = C.EXPERIMENTS["E231"].supports
    assert rule(_keys(0.0, 0.5, 5, 1)) and not rule(_keys(1.0, 0.0, 5, 0))


def test_t26_credits_only_the_confirmatory_e234_not_e230_or_e231():
    """rev3: E230 is the one of four reference sets that does not reject; only its confirmation on fresh seeds
    (E234, declared before it ran) may credit T26, under the same rule."""
    claim = next(c for c in C.CLAIMS if c.id == "T26-hardware-optimism")
    assert "E234" in claim.explain and "E230" not in claim.explain and "E231" not in claim.explain
    assert C.EXPERIMENTS["E234"].supports is C.EXPERIMENTS["E230"].supports


def test_stream_and_own_position_keys_come_under_their_own_groups():
    from probecommit.studies.explain.rig import VARIANTS, keys

    rows = pd.DataFrame([{"session": 1, "instance_id": f"p{i}", "k": 1, "predicted": 0.5, "realized": float(i % 2),
                          "covered": True, "escaped": False, "entered": 1.0, "aim_error": 1.0} for i in range(4)])
    boundary = pd.DataFrame({"session": [1], "first_resolved_mm": [float("nan")], "holds_to_mm": [14.0],
                             "sweep_end_mm": [14.0]})
    got = keys(rows, boundary, {"resamples": 200, "seed": 0},
               {"streams": rows.assign(realized=1.0), "own_positions": rows})  # +0.5 beyond the bound; 0.0 within
    assert got["streams.optimism.sessions_failing_at_least.1"] == 1 and got["streams.optimism.sessions"] == 1
    assert got["own_positions.optimism.share_sessions_paper_outcome"] == 1.0
    assert set(VARIANTS) == {"central", "streams", "own_positions", "confirm"}


def test_e234_seeds_are_fresh_and_declared():
    """E234's seeds overlap no other redraw's (E223/E225/E230/E231 use rig_redraw_seed onwards)."""
    from probecommit.studies.explain.rig import confirm_seeds
    from probecommit.studies.explain.study import load_explain_config

    cfg = load_explain_config(None)
    used = set(range(int(cfg["rig_redraw_seed"]), int(cfg["rig_redraw_seed"]) + int(cfg["rig_redraws"])))
    fresh = confirm_seeds(cfg, quick=False)
    assert len(fresh) == 200 and not used & set(fresh) and len(confirm_seeds(cfg, quick=True)) == 2


@pytest.mark.slow
def test_a_stream_redraw_changes_the_taps_and_a_positions_redraw_keeps_ours(tmp_path):
    """E230's sessions tap elsewhere than E223's at the same positions; E231's keep the frozen positions."""
    from probecommit.robot.session import load_session
    from probecommit.studies.explain import rig
    from probecommit.studies.robot import rig_config

    own = int(rig_config(quick=True).instances.seed)
    fixed = rig.redrawn_sessions(tmp_path, [1001], quick=True)[0][1]
    moved = rig.redrawn_sessions(tmp_path, [1001], quick=True, streams=True)[0][1]
    kept = rig.redrawn_sessions(tmp_path, [1001], quick=True, positions=own)[0][1]
    frozen = rig.redrawn_sessions(tmp_path, [own], quick=True)[0][1]
    (_, a, ta, _), (_, b, tb, _) = load_session(fixed), load_session(moved)
    assert ta == tb and [e.probes for e in a.values()] != [e.probes for e in b.values()]
    assert load_session(kept)[2] == load_session(frozen)[2]
    assert load_session(kept)[0].seed == 1001 and load_session(frozen)[0].seed == rig_config(quick=True).seed
