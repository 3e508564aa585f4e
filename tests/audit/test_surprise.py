"""Prequential surprise: running maximum and its rank AUC for final-budget escape."""

from pathlib import Path

import numpy as np
import pytest

from probecommit.audit.io import read_episodes
from probecommit.audit.surprise import final_escape, max_surprise, surprise_auc

ROBOT = Path(__file__).parent / "data" / "robot_log.csv"


def test_max_surprise_is_running_max_of_negative_log_density():
    lp = np.array([[-1.0, -3.0, -2.0], [-0.5, -0.1, -4.0]])
    np.testing.assert_array_equal(max_surprise(lp), [[1.0, 3.0, 3.0], [0.5, 0.5, 4.0]])


def test_surprise_auc_on_robot_log_by_hand():
    df = read_episodes(ROBOT)
    lab = final_escape(df)
    assert lab.to_dict() == {("pos_0.0", 0): False, ("pos_0.0", 1): False, ("pos_7.5", 0): True,
                             ("pos_m9.8", 0): False, ("pos_m9.8", 1): True}
    auc = surprise_auc(df, resamples=200).set_index("k")
    # k = 1: escaped {1.5, 1.7} vs not {1.2, 1.1, 1.3}; the failed trajectory has no label.
    assert auc.loc[1, "auc"] == pytest.approx(1.0)
    assert (auc.loc[1, "n_escaped"], auc.loc[1, "n_covered"]) == (2, 3)
    # k = 3: escaped {1.6, 3.0} vs {2.0, 1.4, 1.0}: 5 of 6 pairs ordered.
    assert auc.loc[3, "auc"] == pytest.approx(5 / 6)
    assert auc.loc[3, "auc_lo"] <= auc.loc[3, "auc"] <= auc.loc[3, "auc_hi"]
