"""Audit rows from beliefs without particles (audit/gaussian.py): hand cases for one Gaussian and a
mixture, and an EKF-style robot log audited end to end (coverage near nu when the filter is right,
far below when it is overconfident; escape defined by the 4-sigma hull)."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.gaussian import belief_intervals, gaussian_row, mixture_row
from probecommit.audit.pipeline import audit

Z80 = NormalDist().inv_cdf(0.9)  # 1.2815515655446004
ROW = {"instance_id": "p0", "k": 2, "action": 0.0, "predicted": 0.1, "realized": 0.0}


def test_one_gaussian_by_hand():
    row = gaussian_row(mean=[1.0, 5.0], cov=[[4.0, 0.3], [0.3, 1.0]], z_true=3.0, domain_width=10.0, **ROW)
    assert (row["retained_lo"], row["retained_hi"]) == (1.0 - 2 * Z80, 1.0 + 2 * Z80)
    assert (row["hull_lo"], row["hull_hi"]) == (-7.0, 9.0) and row["post_var"] == 4.0
    assert row["covered"] and not row["escaped"]
    assert row["score_s"] == pytest.approx(2 * NormalDist().cdf(1.0) - 1, abs=1e-15)  # 0.6827: one sd out


def test_escape_past_the_four_sigma_hull_and_its_score():
    row = gaussian_row(mean=[0.0], cov=[[1.0]], z_true=-4.5, domain_width=2.0, **ROW)
    assert row["escaped"] and not row["covered"] and row["score_s"] == 1.25 and row["hull_sigmas"] == 4.0
    inside = gaussian_row(mean=[0.0], cov=[[1.0]], z_true=3.99, hull_sigmas=4.0, **ROW)
    assert not inside["escaped"]


def test_a_decision_coordinate_weighing_two_latents():
    found = belief_intervals([1.0], [[1.0, 2.0]], [[[1.0, 0.5], [0.5, 2.0]]], decision=[1.0, -1.0], nu=0.5)
    s = np.sqrt(1.0 + 2.0 - 2 * 0.5)
    assert found["z_mean"] == -1.0 and found["post_var"] == pytest.approx(s**2, abs=1e-15)
    assert found["retained_hi"] == pytest.approx(-1.0 + s * NormalDist().inv_cdf(0.75), abs=1e-15)


def test_a_mixture_central_interval_holds_nu_of_its_mass():
    w, means, covs = [0.3, 0.7], [[-2.0], [1.0]], [[[1.0]], [[0.25]]]
    found = belief_intervals(w, means, covs, nu=0.8)
    cdf = lambda x: 0.3 * NormalDist(-2, 1).cdf(x) + 0.7 * NormalDist(1, 0.5).cdf(x)  # noqa: E731
    assert cdf(found["retained_lo"]) == pytest.approx(0.1, abs=1e-9)
    assert cdf(found["retained_hi"]) == pytest.approx(0.9, abs=1e-9)
    assert (found["hull_lo"], found["hull_hi"]) == (-6.0, 3.0)
    assert found["post_var"] == pytest.approx(0.3 * 5 + 0.7 * 1.25 - (0.3 * -2 + 0.7) ** 2, abs=1e-12)
    one = mixture_row(weights=[2.0], means=[[0.5]], covs=[[[0.09]]], z_true=0.6, **ROW)
    assert one == gaussian_row(mean=[0.5], cov=[[0.09]], z_true=0.6, **ROW)


def test_bad_beliefs_are_refused_in_one_line():
    with pytest.raises(ValueError, match="variance must be > 0"):
        gaussian_row(mean=[0.0], cov=[[0.0]], z_true=0.0, **ROW)
    with pytest.raises(ValueError, match="2 weights for 1 components"):
        mixture_row(weights=[0.5, 0.5], means=[[0.0]], covs=[[[1.0]]], z_true=0.0, **ROW)


def ekf_log(n: int, assumed_noise: float, seed: int = 0) -> list[dict]:
    """An EKF robot's log: latent (offset, gain) ~ N(prior), readings y = offset + gain * tanh(u) + noise at
    probes u = -1, 0.5, 2; the filter linearizes the reading at its mean (its own noise assumption)."""
    rng = np.random.default_rng(seed)
    prior_mean, prior_cov = np.array([0.0, 1.0]), np.diag([1.0, 0.25])
    log = []
    for i in range(n):
        truth = rng.multivariate_normal(prior_mean, prior_cov)
        mean, cov = prior_mean.copy(), prior_cov.copy()
        for u in (-1.0, 0.5, 2.0):
            y = truth[0] + truth[1] * np.tanh(u) + 0.3 * rng.standard_normal()
            jac = np.array([1.0, np.tanh(u)])  # the reading is linear in the latents: the EKF is exact here
            gain = cov @ jac / (jac @ cov @ jac + assumed_noise**2)
            mean = mean + gain * (y - (mean[0] + mean[1] * np.tanh(u)))
            cov = cov - np.outer(gain, jac @ cov)
        log.append({"position": f"p{i}", "mean": mean.tolist(), "cov": cov.tolist(), "action": float(mean[0]),
                    "truth": truth.tolist()})
    return log


def ekf_rows(log: list[dict]) -> pd.DataFrame:
    return pd.DataFrame([gaussian_row(instance_id=r["position"], k=3, mean=r["mean"], cov=r["cov"], z_true=r["truth"][0],
                                      action=r["action"], predicted=0.0, realized=abs(r["action"] - r["truth"][0]),
                                      domain_width=4.0) for r in log])


def test_an_ekf_robot_log_is_audited_with_coverage_and_escape(tmp_path):
    right = ekf_rows(ekf_log(600, assumed_noise=0.3))
    path = tmp_path / "ekf.csv"
    right.to_csv(path, index=False)
    table = audit(path, resamples=200).table
    # Exact Kalman posterior: coverage ~ Binomial(600, 0.8) / 600 (sd 0.016); escape past 4 sigma ~ 6e-5.
    assert table["coverage"].iloc[0] == right["covered"].mean() and abs(table["coverage"].iloc[0] - 0.8) < 0.065
    assert table["escape"].iloc[0] == 0.0 and table["n_episodes"].iloc[0] == 600
    over = ekf_rows(ekf_log(600, assumed_noise=0.03))  # a filter 10x overconfident about its sensor
    assert over["covered"].mean() < 0.5 and over["escaped"].mean() > 0.05
