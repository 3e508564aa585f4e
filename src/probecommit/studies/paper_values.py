"""The paper's reported insertion numbers, for side-by-side comparison only.

These are quoted from the specification (the paper); nothing in the package reads
them to set a parameter. Keys mirror the keys of our results.json.
"""

PAPER = {
    "scan.delta": 0.905,
    "scan.shift_vs_deployed_mm": 2.1,
    "cover.schedule": [-12, -6, 0, 6, 9],
    # Table: insertion failure by split and calibration setting.
    "table_insertion.A.no_probe": 0.820,
    "table_insertion.A.cover_k5": 0.234,
    "table_insertion.B.blind_robust": 0.870,
    "table_insertion.B.cover_k5": 0.255,
    "table_insertion.B.cover_k5_setcal": 0.260,
    "table_insertion.B.cover_k5_setcal_margin": 0.302,
    # Table: insertion audit (Split B, random probes).
    "table_audit.cluster_coverage.original": {1: 0.79, 2: 0.69, 3: 0.55, 5: 0.42, 8: 0.46},
    "table_audit.cluster_coverage.calibrated": {1: 0.81, 2: 0.82, 3: 0.78, 5: 0.76, 8: 0.77},
    "table_audit.optimism.original": {1: 0.115, 2: 0.176, 3: 0.218, 5: 0.263, 8: 0.306},
    "table_audit.optimism.calibrated": {1: -0.003, 2: 0.022, 3: 0.078, 5: 0.047, 8: 0.091},
    "table_audit.mean_abs_coverage_gap": (0.219, 0.025),
    "table_audit.mean_abs_optimism": (0.216, 0.048),
    "text.escape_k1": 0.055,
    "text.escape_k8": 0.169,
    "text.episode_coverage_k1": 0.94,
    "text.episode_coverage_k8": 0.77,
    "calibration.margin_cover": 0.74,
    "calibration.margin_random": 0.62,
    "calibration.distribution_free_margin_cover": 0.90,
    "calibration.t5_cover": 0.42,
    "resplits.level_mean_sd": (0.75, 0.25),
    "resplits.failure_mean_sd": (0.328, 0.025),
    "resplits.heldout_cluster_coverage": 0.857,
    "resplits.margin_optimistic_fraction": 0.64,
    # Table: confirmation on untouched instances (Test C), old vs corrected.
    "table_testc.escape_random_k8": (0.164, 0.000),
    "table_testc.episode_coverage_random_k8": (0.768, 1.000),
    "table_testc.optimism_random_k8": (0.274, -0.015),
    "table_testc.failure_random_k8": (0.354, 0.112),
    "table_testc.failure_cover_k5": (0.326, 0.159),
    "table_testc.failure_cover_k1": (0.721, 0.703),
    "table_testc.failure_cover_k5_setcal_margin": (0.294, 0.193),
    # Table: controlled mismatch tests (failure at random k=8).
    "table_faults.fail": {"none": 0.10, "noise": 0.10, "boundary": 0.38, "prior": 0.29, "particles": 0.13, "frame": 0.26},
    "table_faults.surprise_auc": {"boundary": 0.64, "prior": 0.59, "particles": 0.67},
    "table_faults.tempered": {"noise": 0.10, "boundary": 0.38, "prior": 0.29, "particles": 0.13, "frame": 0.26},
    "table_faults.fixed": {"noise": 0.10, "boundary": 0.10, "prior": 0.18, "particles": 0.10, "frame": 0.10},
    "faults.paired_fix": {"boundary": -0.281, "frame": -0.161, "prior": -0.104, "particles": -0.026},
    # Robust filters (chosen on development, confronted with the boundary error).
    "robust.chosen": {"tempering": 1, "mixture": 0.01, "rejuvenation": 0.02},
    "robust.escape": {"deployed": 0.174, "mixture": 0.042, "rejuvenation": 0.062},
    "robust.failure_diff": {"mixture": 0.016, "rejuvenation": 0.029},
    "robust.mixture_cost_when_right": (0.102, 0.167),
    # The commit decision (Split B, cover schedule, budget-simultaneous threshold).
    "gates.simultaneous_threshold": {"cover": 1.004, "random": 1.018},
    "gates.area": {"raw": 0.293, "posterior_variance": 0.306, "adjusted": 0.407},
    "gates.escaped_committed": {"raw": (43, 230, 7, 154), "adjusted": (41, 231, 9, 153), "posterior_variance": (43, 230, 7, 154)},
    "gates.claimed_realized": {"raw": (0.017, 0.313), "adjusted": (0.075, 0.359)},
    "gates.oracle_commit_rate": 0.89,
    "testc.simultaneous_threshold_corrected": {"cover": 0.046, "random": 0.085},
}
