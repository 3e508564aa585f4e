"""The episode coverage score ``s`` (paper Sec. IV, "The episode score").

Sort particles by descending weight (ties in index order), let ``W_m`` be the
cumulative mass of the first ``m`` and ``I_m`` the range of the decision coordinate
over them. The score is the mass of the shortest prefix covering the truth,
``s = min{W_m : z* in I_m}``, so ``s <= t`` implies ``z*`` lies in the retained
interval at threshold ``t``. When the truth escapes the full hull the score
continues past one: ``s = 1 + d(z*, hull) / D``.
"""

from __future__ import annotations

# The score is computed from a belief, so it lives in core (the runner computes it while
# committing); the audit re-exports it for users scoring their own particles.
from probecommit.core.retained import coverage_score

__all__ = ["coverage_score"]
