"""audit.episode_row: audit rows from a robot's own particles, checked by hand."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.audit import episode_row, validate_episodes


def test_row_from_particles_by_hand():
    z = [0.0, 1.0, 2.0, 10.0]
    w = [0.5, 0.3, 0.15, 0.05]  # top-weight prefix of mass 0.8: particles 0 and 1
    row = episode_row(instance_id="p1", k=2, z_true=1.5, action=0.5, predicted=0.2, realized=1.0,
                      z_particles=z, weights=w, nu=0.8, domain_width=20.0, entered=True)
    assert (row["retained_lo"], row["retained_hi"]) == (0.0, 1.0)
    assert (row["hull_lo"], row["hull_hi"]) == (0.0, 10.0)
    assert row["covered"] is False and row["escaped"] is False
    assert row["n_retained"] == 2 and row["entered"] is True
    # The shortest prefix covering 1.5 needs particle 2: mass 0.95.
    assert row["score_s"] == pytest.approx(0.95)
    mean = np.dot(w, z)
    assert row["post_var"] == pytest.approx(np.dot(w, (np.array(z) - mean) ** 2))


def test_row_from_intervals_and_an_escape():
    row = episode_row(instance_id="p1", k=1, z_true=12.0, action=[1.0, 2.0], predicted=0.1, realized=1.0,
                      retained=(0.0, 3.0), hull=(-1.0, 5.0))
    assert row["escaped"] and not row["covered"] and row["action_1"] == 2.0


def test_rows_pass_the_audit_validation():
    rows = [episode_row(instance_id=f"p{i}", k=1, z_true=0.1 * i, action=0.0, predicted=0.5, realized=float(i % 2),
                        z_particles=np.linspace(-1, 1, 50), weights=np.ones(50)) for i in range(4)]
    import pandas as pd

    table = validate_episodes(pd.DataFrame(rows))
    assert table["covered"].tolist() == [r["covered"] for r in rows]


@pytest.mark.parametrize("bad", [{"z_true": float("nan")}, {"weights": [1.0, -1.0]}, {"weights": None}])
def test_bad_input_is_named(bad):
    kwargs = dict(instance_id="p", k=1, z_true=0.0, action=0.0, predicted=0.1, realized=0.0,
                  z_particles=[0.0, 1.0], weights=[0.5, 0.5])
    kwargs.update(bad)
    with pytest.raises(ValueError, match="episode_row"):
        episode_row(**kwargs)
