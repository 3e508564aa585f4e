"""Every number the paper reports that the reproduction compares with: the one paper-values table.

Why one table of strings: a paper value is quoted, never computed, so it is kept exactly as
the paper prints it (``"+0.115"``, ``"0.79"``, ``"87.0"``). A test checks that every string
occurs in the paper's text; :func:`value` parses it, and :func:`fmt` gives the format spec
that prints it back unchanged, so a paper value reaches published prose through the
ledger (``"paper:<key>"``) like any computed number. Nothing in the package reads these to
set a parameter.

:data:`PRINTED` is the table; :data:`PAPER` keeps a few earlier keys as floats for code written
against them. Keys of :data:`PRINTED` are ``<claim id>.<name>``: the claims registry (:mod:`probecommit.studies.claims`)
names its paper values by these keys. Claim ids use the paper's own labels
(``tab:breadth``, ``fig:decision``) or ``T<nn>-<slug>`` for the numbered claims in the text.
"""

from __future__ import annotations

import re
from typing import Any

_AUDIT_K = (1, 2, 3, 5, 8)


def _rows(prefix: str, names: tuple[str, ...], cells: dict[str, tuple[str, ...]]) -> dict[str, str]:
    """``{prefix.row.name: text}`` for a table given row by row."""
    return {f"{prefix}.{row}.{name}": text for row, values in cells.items() for name, text in zip(names, values)}


PRINTED: dict[str, str] = {
    # ---------------------------------------------------------------- Table I (tab:setup): n per family
    **{f"tab:setup.{fam}.n": n for fam, n in (("insertion", "96{\\times}4"), ("push1d", "81{\\times}6"),
                                               ("push2d", "18{\\times}6"), ("darts", "18{\\times}8"),
                                               ("hinge", "18{\\times}16"), ("shuffleboard", "18{\\times}6"),
                                               ("grasp", "16{\\times}80"))},
    # ---------------------------------------------------------------- Table II (tab:breadth)
    **_rows("tab:breadth", ("blind_bayes", "blind_robust", "probe_robust", "delta", "delta_lo", "delta_hi"), {
        "insertion_A": ("0.820", "", "0.234", "0.586", "0.492", "0.674"),
        "push1d": ("0.491", "", "0.062", "", "", ""),
        "push2d": ("0.252", "0.307", "0.221", "0.031", "0.007", "0.054"),
        "push2d_pybullet": ("0.243", "", "0.141", "", "", ""),
        "darts": ("0.026", "0.035", "0.010", "0.016", "0.009", "0.024"),
        "hinge": ("0.334", "", "0.031", "", "", ""),
        "shuffleboard": ("0.083", "", "0.050", "", "", ""),
        "grasp": ("0.333", "", "0.692", "", "", ""),
    }),
    "tab:breadth.hinge.change_percent": "-91",
    "tab:breadth.shuffleboard.blind_bayes_p90": "0.199",
    "tab:breadth.shuffleboard.probe_robust_p90": "0.123",
    "tab:breadth.push2d_pybullet.residual_model": "0.115",
    # ---------------------------------------------------------------- Table III (tab:audit)
    **{f"tab:audit.cluster_coverage_original.{k}": v for k, v in zip(_AUDIT_K, ("0.79", "0.69", "0.55", "0.42", "0.46"))},
    **{f"tab:audit.cluster_coverage_calibrated.{k}": v for k, v in zip(_AUDIT_K, ("0.81", "0.82", "0.78", "0.76", "0.77"))},
    **{f"tab:audit.optimism_original.{k}": v for k, v in zip(_AUDIT_K, ("+0.115", "+0.176", "+0.218", "+0.263", "+0.306"))},
    **{f"tab:audit.optimism_calibrated.{k}": v for k, v in zip(_AUDIT_K, ("-0.003", "+0.022", "+0.078", "+0.047", "+0.091"))},
    "tab:audit.mean_abs_coverage_gap.original": "0.219",
    "tab:audit.mean_abs_coverage_gap.calibrated": "0.025",
    "tab:audit.mean_abs_optimism.original": "0.216",
    "tab:audit.mean_abs_optimism.calibrated": "0.048",
    # ---------------------------------------------------------------- Table IV (tab:insertion)
    **_rows("tab:insertion", ("est", "lo", "hi"), {
        "A_no_probe": ("0.820", "0.779", "0.859"),
        "A_cover_k5": ("0.234", "0.159", "0.312"),
        "B_blind_robust": ("0.870", "0.836", "0.901"),
        "B_cover_k5": ("0.255", "0.211", "0.299"),
        "B_cover_k5_setcal": ("0.260", "0.182", "0.341"),
        "B_cover_k5_setcal_margin": ("0.302", "0.221", "0.385"),
    }),
    # ---------------------------------------------------------------- Table V (tab:testc)
    **_rows("tab:testc", ("old", "corrected", "diff", "diff_lo", "diff_hi"), {
        "escape_random_k8": ("0.164", "0.000", "+0.164", "+0.125", "+0.203"),
        "episode_coverage_random_k8": ("0.768", "1.000", "-0.232", "-0.279", "-0.188"),
        "optimism_random_k8": ("+0.274", "-0.015", "+0.289", "+0.234", "+0.344"),
        "failure_random_k8": ("0.354", "0.112", "+0.242", "+0.188", "+0.297"),
        "failure_cover_k5": ("0.326", "0.159", "+0.167", "+0.091", "+0.247"),
        "failure_cover_k1": ("0.721", "0.703", "+0.018", "-0.016", "+0.052"),
        "failure_cover_k5_setcal_margin": ("0.294", "0.193", "+0.102", "+0.031", "+0.180"),
    }),
    # ---------------------------------------------------------------- Table VI (tab:engines)
    **_rows("tab:engines", ("support_escape", "episode_coverage", "optimism_e_k", "failure"), {
        "pybullet/deployed": ("0.167", "0.763", "+0.232", "0.307"),
        "pybullet/mj_offset": ("0.023", "0.951", "+0.002", "0.109"),
        "pybullet/own_scan": ("0.031", "0.948", "-0.002", "0.107"),
        "sapien/deployed": ("0.039", "0.914", "+0.369", "0.474"),
        "sapien/mj_offset": ("0.065", "0.872", "+0.419", "0.534"),
        "sapien/own_scan": ("0.000", "0.995", "+0.338", "0.469"),
    }),
    # ---------------------------------------------------------------- Table VII (tab:hardware), physical arm
    **_rows("tab:hardware", ("episodes", "in_window", "entered", "predicted", "realized", "optimism"), {
        "1": ("26", "6", "19", "0.657", "0.769", "+0.112"),
        "2": ("21", "13", "18", "0.474", "0.381", "-0.093"),
        "3": ("26", "19", "24", "0.315", "0.269", "-0.046"),
        "4": ("21", "15", "21", "0.225", "0.286", "+0.061"),
        "5": ("24", "22", "24", "0.084", "0.083", "-0.001"),
    }),
    "tab:hardware.window_mm": "6.57",
    # ---------------------------------------------------------------- Table VIII (tab:faults)
    **_rows("tab:faults", ("fail", "surprise", "tempered", "fix"), {
        "none": ("0.10", "", "", ""),
        "noise": ("0.10", "", "0.10", "0.10"),
        "boundary": ("0.38", "0.64", "0.38", "0.10"),
        "prior": ("0.29", "0.59", "0.29", "0.18"),
        "particles": ("0.13", "0.67", "0.13", "0.10"),
        "frame": ("0.26", "", "0.26", "0.10"),
    }),
    "tab:faults.half_width_max": "0.077",
    # ---------------------------------------------------------------- numbered claims in the text
    "T01-pricing.blind_above.darts": "1.2",
    "T01-pricing.blind_above.push2d": "1.7",
    "T01-pricing.blind_above.hinge": "0.17",
    "T01-pricing.blind_above.push1d": "35",
    "T01-pricing.five_below.darts": "0.06",
    "T01-pricing.five_below.push2d": "1.7",
    "T01-pricing.five_below.hinge": "0.012",
    "T01-pricing.five_below.push1d": "1.9",
    "T02-t5-cover.t5": "0.42",
    "T03-margin.cover": "0.74",
    "T03-margin.random": "0.62",
    "T04-distribution-free-margin.cover": "0.90",
    "T05-escape-realizations.audit": "0.169",
    "T05-escape-realizations.faults": "0.174",
    "T05-escape-realizations.testc": "0.164",
    "T06-cover-failure-splits.A": "0.234",
    "T06-cover-failure-splits.B": "0.255",
    "T06-cover-failure-splits.C": "0.326",
    "T07-cover-schedule.schedule": "[-12,-6,0,6,9]",
    "T07-cover-schedule.subsets": "126",
    "T08-paired-reductions.count": "three",
    "T09-grasp.improve": "three of six",
    "T09-grasp.improve_min": "0.36",
    "T09-grasp.improve_max": "0.96",
    "T09-grasp.p": "0.25",
    "T10-gru.gru": "0.153",
    "T10-gru.pipeline": "0.157",
    "T10-gru.diff": "-0.004",
    "T10-gru.diff_lo": "-0.008",
    "T10-gru.diff_hi": "+0.000",
    "T10-gru.margin": "0.020",
    "T11-audit-trend.coverage_k1": "0.94",
    "T11-audit-trend.coverage_k8": "0.77",
    "T11-audit-trend.escape_k1": "5.5",
    "T11-audit-trend.escape_k8": "16.9",
    "T11-audit-trend.e8": "+0.31",
    "T12-calibrated-audit.optimism_original": "0.216",
    "T12-calibrated-audit.optimism_calibrated": "0.048",
    "T13-cost-of-calibration.full": "+0.047",
    "T13-cost-of-calibration.full_lo": "+0.005",
    "T13-cost-of-calibration.full_hi": "+0.091",
    "T13-cost-of-calibration.set": "+0.005",
    "T13-cost-of-calibration.set_lo": "-0.010",
    "T13-cost-of-calibration.set_hi": "+0.021",
    "T13-cost-of-calibration.margin": "+0.042",
    "T13-cost-of-calibration.margin_lo": "0.000",
    "T13-cost-of-calibration.margin_hi": "+0.083",
    "T14-resplits.level_mean": "0.75",
    "T14-resplits.level_sd": "0.25",
    "T14-resplits.failure_mean": "0.328",
    "T14-resplits.failure_sd": "0.025",
    "T14-resplits.heldout_cluster_coverage": "0.857",
    "T14-resplits.margin_optimistic_percent": "64",
    "T15-scan.delta": "+0.905",
    "T15-scan.shift": "2.1",
    "T15-scan.scans": "48",
    "T16-corrected-thresholds.cover": "0.046",
    "T16-corrected-thresholds.random": "0.085",
    "T18-engine-scans.pybullet_offset": "0.929",
    "T18-engine-scans.sapien_offset": "-0.209",
    "T18-engine-scans.pybullet_ratio": "1.21",
    "T18-engine-scans.pybullet_ratio_sd": "0.69",
    "T18-engine-scans.sapien_ratio": "0.55",
    "T19-pybullet-escape.k1": "0.055",
    "T19-pybullet-escape.k8": "0.167",
    "T19-pybullet-escape.mujoco_k8": "0.174",
    "T20-pybullet-transfer.mj_offset": "-0.198",
    "T20-pybullet-transfer.mj_offset_lo": "-0.253",
    "T20-pybullet-transfer.mj_offset_hi": "-0.143",
    "T20-pybullet-transfer.own_scan": "-0.200",
    "T20-pybullet-transfer.own_scan_lo": "-0.255",
    "T20-pybullet-transfer.own_scan_hi": "-0.148",
    "T21-physx-cluster-coverage.cluster_coverage": "0.72",
    "T22-physx-paired.mj_offset": "+0.060",
    "T22-physx-paired.mj_offset_lo": "-0.003",
    "T22-physx-paired.mj_offset_hi": "0.122",
    "T22-physx-paired.own_scan": "-0.005",
    "T22-physx-paired.own_scan_lo": "-0.076",
    "T22-physx-paired.own_scan_hi": "0.062",
    "T23-hardware-guards.pass": "12",
    "T23-hardware-guards.positions": "14",
    "T24-hardware-coverage.episodes": "118",
    "T25-hardware-gain.entered_1": "19",
    "T25-hardware-gain.episodes_1": "26",
    "T25-hardware-gain.entered_5": "24",
    "T25-hardware-gain.episodes_5": "24",
    "T25-hardware-gain.aim_error_1": "12.6",
    "T25-hardware-gain.aim_error_5": "3.6",
    "T26-hardware-optimism.bound": "0.12",
    "T27-replay-deployed.coverage": "1.000",
    "T27-replay-deployed.optimism": "0.000",
    "T28-replay-boundary.first_mm": "8",
    "T28-replay-boundary.optimism": "+0.11",
    "T28-replay-boundary.optimism_lo": "+0.04",
    "T28-replay-boundary.optimism_hi": "+0.18",
    "T28-replay-boundary.coverage_holds_mm": "14",
    "T29-replay-prior.coverage": "0.61",
    "T29-replay-prior.escape": "0.39",
    "T29-replay-prior.optimism": "+0.30",
    "T30-original-thresholds.cover": "1.004",
    "T30-original-thresholds.random": "1.018",
    "T31-gate-areas.raw": "0.293",
    "T31-gate-areas.posterior_variance": "0.306",
    "T31-gate-areas.adjusted": "0.407",
    "T32-gate-areas-random.posterior_variance": "0.325",
    **_rows("T33-committed-pool", ("escaped_committed", "n_committed", "escaped_rejected", "n_rejected"), {
        "raw": ("43", "230", "7", "154"), "adjusted": ("41", "231", "9", "153"),
        "posterior_variance": ("43", "230", "7", "154")}),
    "T34-claimed-realized.raw_claimed": "0.017",
    "T34-claimed-realized.raw_realized": "0.313",
    "T34-claimed-realized.adjusted_claimed": "0.075",
    "T34-claimed-realized.adjusted_realized": "0.359",
    "T35-oracle.commit_rate_percent": "89",
    "T36-surprise.auc_k1": "0.85",
    "T36-surprise.auc_k5": "0.54",
    "T36-surprise.auc_k5_lo": "0.46",
    "T36-surprise.auc_k5_hi": "0.63",
    "T36-surprise.escaped": "50",
    "T36-surprise.covered": "334",
    "T37-prior-signature.escape": "0.25",
    "T38-boundary-signature.escape_first": "0.07",
    "T38-boundary-signature.escape_last": "0.17",
    "T38-boundary-signature.optimism_first": "+0.07",
    "T38-boundary-signature.optimism_last": "+0.30",
    "T40-frame-signature.coverage": "1.00",
    "T40-frame-signature.fail": "0.26",
    "T41-paired-fixes.boundary": "-0.281",
    "T41-paired-fixes.boundary_lo": "-0.352",
    "T41-paired-fixes.boundary_hi": "-0.214",
    "T41-paired-fixes.frame": "-0.161",
    "T41-paired-fixes.frame_lo": "-0.219",
    "T41-paired-fixes.frame_hi": "-0.107",
    "T41-paired-fixes.prior": "-0.104",
    "T41-paired-fixes.prior_lo": "-0.167",
    "T41-paired-fixes.prior_hi": "-0.044",
    "T41-paired-fixes.particles": "-0.026",
    "T41-paired-fixes.particles_lo": "-0.057",
    "T41-paired-fixes.particles_hi": "+0.003",
    "T42-robust-chosen.tempering": "1",
    "T42-robust-chosen.mixture": "0.01",
    "T42-robust-chosen.rejuvenation": "0.02",
    "T43-robust-filters.escape_deployed": "0.174",
    "T43-robust-filters.escape_mixture": "0.042",
    "T43-robust-filters.escape_rejuvenation": "0.062",
    "T43-robust-filters.mixture": "+0.016",
    "T43-robust-filters.mixture_lo": "-0.008",
    "T43-robust-filters.mixture_hi": "+0.039",
    "T43-robust-filters.rejuvenation": "+0.029",
    "T43-robust-filters.rejuvenation_lo": "-0.003",
    "T43-robust-filters.rejuvenation_hi": "+0.062",
    "T43-robust-filters.optimism_floor": "+0.29",
    "T44-mixture-cost.right": "0.102",
    "T44-mixture-cost.mixture": "0.167",
    # ---------------------------------------------------------------- figures
    "fig:decision.oracle_commit_percent": "89",
    "fig:signatures.n": "384",
}
# Empty strings mark cells the paper leaves blank ("--"); they are not values.
PRINTED = {key: text for key, text in PRINTED.items() if text != ""}

_NUMBER = re.compile(r"^[+-]?\d+(\.\d+)?$")


def is_number(key: str) -> bool:
    """Whether the paper value under ``key`` is a single printed number."""
    return bool(_NUMBER.match(PRINTED[key]))


def value(key: str) -> float:
    """The paper value under ``key`` as a float (KeyError for an unknown key)."""
    text = PRINTED[key]
    if not _NUMBER.match(text):
        raise ValueError(f"paper value {key} = {text!r} is not a single number")
    return float(text)


def fmt(key: str) -> str:
    """The format spec that prints ``value(key)`` back exactly as the paper does."""
    text = PRINTED[key]
    sign = "+" if text.startswith("+") else ""
    if "." not in text:
        return "d" if not sign else "+d"
    return f"{sign}.{len(text.split('.')[1])}f"


def tree() -> dict[str, Any]:
    """The numeric paper values as the ledger's ``"paper"`` source (``"paper:<key>"``)."""
    return {key: value(key) for key in PRINTED if is_number(key)}


def seed_form(key: str) -> str:
    """The text as it stands in the paper's LaTeX source (for the test against the seed)."""
    return PRINTED[key]


#: Earlier keys, as floats (and the cover schedule as a list), for code written against them.
LEGACY_KEYS = {"calibration.t5_cover": "T02-t5-cover.t5", "calibration.margin_cover": "T03-margin.cover",
               "calibration.margin_random": "T03-margin.random",
               "calibration.distribution_free_margin_cover": "T04-distribution-free-margin.cover",
               "scan.delta": "T15-scan.delta", "scan.shift_vs_deployed_mm": "T15-scan.shift",
               "text.escape_k8": "T05-escape-realizations.audit", "gates.oracle_commit_rate": "T35-oracle.commit_rate_percent"}
PAPER: dict[str, Any] = {old: value(new) for old, new in LEGACY_KEYS.items()}

#: T14's re-split statistics a fresh-pool experiment tests (E56, E205; the registry and ex35's step both read this one
#: table): label, the pools' row column, paper key, and the scale that puts the paper's value on the rows' units.
RESPLIT_STATS = (("level mean", "level_mean", "T14-resplits.level_mean", 1.0),
                 ("held-out cluster coverage", "heldout_cluster_coverage", "T14-resplits.heldout_cluster_coverage", 1.0),
                 ("margin optimistic", "margin_optimistic_fraction", "T14-resplits.margin_optimistic_percent", 0.01))
PAPER["gates.oracle_commit_rate"] /= 100
PAPER["cover.schedule"] = [int(u) for u in PRINTED["T07-cover-schedule.schedule"].strip("[]").split(",")]
