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
    assert got["positions"] == 2 and got["share_beyond"] == 0.5 and got["escape_is_beyond"] == 1
    assert got["optimism_beyond"] == pytest.approx(0.7) and got["optimism_inside"] == pytest.approx(-0.3)
    assert got["optimism_at_share"] == pytest.approx(0.25 * 0.7 + 0.75 * -0.3)


def test_a_position_inside_that_escapes_breaks_the_mechanism():
    sweep, session = _rows([("a", -15.0, [(0.2, 1.0, True)]), ("b", 3.0, [(0.5, 0.0, True)])])
    assert prior_by_position(sweep, session, 12.0)["escape_is_beyond"] == 0


def test_e222_needs_the_mechanism_and_the_papers_optimism_at_its_share():
    rule = C.EXPERIMENTS["E222"].supports
    paper = C.paper_values.value("T29-replay-prior.optimism")
    assert rule({"m": 1, "o": paper + 0.04}) and not rule({"m": 0, "o": paper}) and not rule({"m": 1, "o": paper + 0.06})
