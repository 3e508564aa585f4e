"""The GRU baseline: training lowers the loss and is bit-identical, checkpoints resume, the test decides."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the GRU baseline needs torch (pip install 'probecommit[gru]')")

from probecommit.baselines.gru import TrainingConfig, encode_history, equivalent, make_training_set, train, train_or_resume  # noqa: E402
from probecommit.tasks.push2d.model import Push2DModel  # noqa: E402

TINY = TrainingConfig(samples=300, steps=60, batch=64, hidden=16)


@pytest.fixture(scope="module")
def data():
    return Push2DModel(), make_training_set(Push2DModel(), np.array([[0.5, 0.2], [1.0, -0.3]]), TINY, 3)


def test_tiny_training_lowers_the_loss_and_repeats_bit_for_bit(data):
    model, d = data
    state_a, curve_a = train(d, model, TINY, 0)
    state_b, curve_b = train(d, model, TINY, 0)
    assert np.mean(curve_a[-10:]) < np.mean(curve_a[:10])
    assert curve_a == curve_b
    assert all(torch.equal(state_a[k], state_b[k]) for k in state_a)


def test_a_checkpointed_seed_is_not_retrained(data, tmp_path, monkeypatch):
    model, d = data
    first, _ = train_or_resume(tmp_path, d, model, TINY, 1)
    import probecommit.baselines.gru as gru

    monkeypatch.setattr(gru, "train", lambda *a, **k: (_ for _ in ()).throw(AssertionError("retrained")))
    again, meta = train_or_resume(tmp_path, d, model, TINY, 1)
    assert meta["seed"] == 1 and all(torch.equal(first[k], again[k]) for k in first)


def test_the_equivalence_test_accepts_and_rejects_where_it_must():
    assert equivalent((-0.004, -0.008, 0.0), 0.020)  # the paper's
    assert not equivalent((0.01, -0.005, 0.025), 0.020)  # straddles the margin
    assert not equivalent((0.05, 0.03, 0.08), 0.020)  # entirely outside
    assert not equivalent((0.0, -0.020, 0.010), 0.020)  # touching the margin is not inside


def test_history_encoding_is_order_sensitive_and_handles_budget_zero():
    u = np.array([[[1.0], [3.0]]])
    y = np.array([[[0.1, 0.0], [0.5, 0.0]]])
    ctx = np.array([[1.0, 0.2]])
    forward = encode_history(u, y, ctx, 3.0, 1.0)
    backward = encode_history(u[:, ::-1], y[:, ::-1], ctx, 3.0, 1.0)
    assert forward.shape == (1, 2, 6) and not np.array_equal(forward, backward)
    empty = encode_history(u[:, :0], y[:, :0], ctx, 3.0, 1.0)
    assert empty.shape == (1, 1, 6) and empty[0, 0, -1] == 0 and np.allclose(empty[0, 0, 3:5], ctx[0])


def test_seeds_trained_in_parallel_processes_equal_those_trained_here(tmp_path):
    """``reproduce gru --workers N``: each seed trained in a spawned process, checkpointed; the one-by-one
    loop reads back the same weights and loss it would have trained itself."""
    from probecommit.studies.gru import train_in_parallel

    model, contexts, data_seed = Push2DModel(), np.array([[0.5, 0.2], [1.0, -0.3]]), 3
    train_in_parallel(tmp_path / "parallel", model, contexts, TINY, data_seed, 2, 2, lambda *args: None)
    for seed in range(2):
        here, meta_here = train_or_resume(tmp_path / "here", make_training_set(model, contexts, TINY, data_seed + seed),
                                          model, TINY, seed)
        read, meta_read = train_or_resume(tmp_path / "parallel", make_training_set(model, contexts, TINY, data_seed + seed),
                                          model, TINY, seed)
        assert all(torch.equal(here[k], read[k]) for k in here)
        assert meta_here == meta_read
