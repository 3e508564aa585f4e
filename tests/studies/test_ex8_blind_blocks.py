"""ex8_blind's redrawn cells over blocks of truths are the whole ``[actions, truths]`` matrix's, bit for bit (issue 42)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.explain import ex8_blind


@pytest.mark.parametrize("family", ["push2d", "darts"])
def test_blocks_give_the_whole_matrix_cells(family: str, monkeypatch: pytest.MonkeyPatch) -> None:
    model = ex8_blind._model(family)
    rng = np.random.default_rng(5)
    n_actions = len(model.action_grid[0])
    rows = pd.DataFrame({**{f"action_{i}": rng.choice(model.action_grid[:, i], 12) for i in range(n_actions)},
                         **{f"true_{n}": 0.0 for n in model.latent_names},
                         "ctx_0": np.repeat([2.0, 3.0], 6), **({"ctx_1": 0.3} if family == "push2d" else {})})
    whole = ex8_blind.redraw_cells(rows, model, n_truths=7, draws=9, seed=1)
    for block in (1, 2, 5, 10**6):
        monkeypatch.setattr(ex8_blind, "REDRAW_BLOCK", block)
        assert ex8_blind.redraw_cells(rows, model, n_truths=7, draws=9, seed=1).tobytes() == whole.tobytes(), block
