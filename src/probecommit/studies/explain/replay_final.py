"""A replay committed at one budget only: what a step that reads the final budget alone needs (issue 42).

Several explain steps replay a stored run under another belief and read only the Probe-Robust rows at
the final budget (the mixture when the model is right, E46's 20 filter seeds, ex7's harness draws):
``replay_episodes`` commits every budget (and the blind arms at the prior), so most of each replay's
commits and engine queries were thrown away. An episode's belief at budget ``k`` does not depend on
which budgets are kept (``RunBeliefs.of(..., budgets=...)``, tested in the runner), so the rows at ``k``
are the same bits as those of the full replay.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pandas as pd

from probecommit.runner.replay import LoadedRun, replay_commit, committed_budgets, require_budgets


def replay_at(loaded: LoadedRun, overrides: dict[str, dict[str, Any]] | None, k: int,
              chunk_instances: int | None = 48) -> pd.DataFrame:
    """``replay_episodes(loaded, overrides, chunk_instances=...)``'s rows at budget ``k`` (every method
    committed there; no failed-rollout rows, which no caller of it reads): the same checks, model,
    executors and thresholds, with only budget ``k``'s beliefs kept and committed."""
    beliefs, request, common = replay_commit(loaded, overrides, None, None, False, chunk_instances)
    kept = tuple(require_budgets([int(k)], committed_budgets(beliefs.config)))  # refuses a budget the run lacks
    beliefs = replace(beliefs, kept_budgets=kept)
    [episodes] = beliefs.commit([request], **common)
    return episodes
