"""Offline audit and calibration (paper Sec. IV and VI). NumPy + pandas only.

Modules: ``io`` (read/validate episode tables), ``metrics`` (per-budget audit),
``stats`` (cluster bootstrap, paired differences, sign-flip test, rank AUC),
``conformal`` (thresholds), ``margin``, ``gates``, ``surprise``, ``score`` (the
episode coverage score), ``report`` (HTML) and ``pipeline`` (the audit of a table or
run directory). Tables only: calibration and gates that re-commit episodes are in
``probecommit.runner.calibration``.
"""

from probecommit.audit.conformal import (
    conformal_quantile,
    fixed_budget_thresholds,
    instance_scores,
    simultaneous_scores,
    simultaneous_threshold,
)
from probecommit.audit.gaussian import belief_intervals, gaussian_row, mixture_row
from probecommit.audit.gates import evaluate_gates, first_passage, gate_curve, gates_from_tables
from probecommit.audit.io import EpisodeTableError, read_episodes, validate_episodes
from probecommit.audit.margin import GAMMA_GRID, distribution_free_margin, select_margin
from probecommit.audit.metrics import audit_table
from probecommit.audit.score import coverage_score
from probecommit.audit.stats import (
    Interval,
    cluster_bootstrap_auc,
    cluster_bootstrap_mean,
    paired_bootstrap,
    rank_auc,
    sign_flip_test,
)
from probecommit.audit.surprise import max_surprise, surprise_auc


from probecommit.audit.pipeline import AuditResult, audit
from probecommit.audit.rows import episode_row

__all__ = [
    "AuditResult", "audit", "EpisodeTableError", "GAMMA_GRID", "Interval", "audit_table", "cluster_bootstrap_auc",
    "cluster_bootstrap_mean", "conformal_quantile", "coverage_score", "distribution_free_margin", "episode_row",
    "gaussian_row",
    "mixture_row",
    "belief_intervals",
    "evaluate_gates", "first_passage", "fixed_budget_thresholds", "gate_curve", "gates_from_tables",
    "instance_scores", "max_surprise", "paired_bootstrap", "rank_auc", "read_episodes", "select_margin",
    "sign_flip_test", "simultaneous_scores", "simultaneous_threshold", "surprise_auc", "validate_episodes",
]
