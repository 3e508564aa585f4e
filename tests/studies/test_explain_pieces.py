"""A sweep cut into pieces set aside as processes of their own (``Explain.split``, issue 42 target 4): its keys and
stored rows are those of the sweep run as one step, in the same places, whatever order the pieces ran in."""

from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.explain import ex38_physx as ex38
from probecommit.studies.explain import ex39_pybullet as ex39
from probecommit.studies.explain.pieces import Pieces, in_place
from probecommit.studies.explain.study import Explain


def _point(arm: str, value: float) -> pd.DataFrame:
    """A piece: its rows, and the process it ran in."""
    return pd.DataFrame({"arm": [arm, arm], "value": [value, value], "row": [0, 1], "pid": [os.getpid()] * 2})


def _combine(parts: list[pd.DataFrame]) -> dict:
    rows = pd.concat(parts, ignore_index=True)
    return {"res": {"gru": {f"{r.arm}.{r.value}.{r.row}": float(r.value) for r in rows.itertuples()}},
            "stored": {"toy.parquet": rows}}


def _plan(job: Explain) -> Pieces:
    """Three pieces; the cheap one first in call order, so the submission order differs from it."""
    calls = [(_point, ("a", 1.0)), (_point, ("b", 2.0)), (_point, ("a", 3.0))]
    return Pieces(calls, [1.0, 5.0, 5.0], _combine)


def _fill_after(job: Explain) -> None:
    job.res["gru"].update(z=3.0)


def _steps(job: Explain, split: bool) -> list:
    before, after = (lambda: job.res["gru"].update(first=0.0)), (lambda: job.res["gru"].update(after=9.0))
    if split:
        return [before, job.split(_plan), after, job.aside(_fill_after), job.split(lambda j: None)]
    return [before, lambda: in_place(job, _plan), after, lambda: _fill_after(job)]


def test_pieces_are_submitted_longest_first_ties_in_call_order():
    assert Pieces([None] * 4, [1.0, 5.0, 2.0, 5.0], _combine).order() == [1, 3, 2, 0]
    with pytest.raises(ValueError, match="3 pieces, 2 costs"):
        Pieces([None] * 3, [1.0, 2.0], _combine)
    with pytest.raises(ValueError, match="no pieces"):
        Pieces([], [], _combine)


@pytest.mark.parametrize("cpus", [None, 1])
def test_a_split_sweep_fills_what_the_sweep_in_place_fills_where_it_would(tmp_path, monkeypatch, cpus):
    """On several CPUs each piece in a process of its own; on one (``cpus=1``) inline, handed on at once."""
    if cpus is not None:
        monkeypatch.setattr("probecommit.studies.explain.background.os.cpu_count", lambda: cpus)
    jobs = {}
    for split in (True, False):
        job = jobs[split] = Explain(tmp_path, True, lambda *a: None, 1, {})
        job.run_steps(_steps(job, split))
    keys = ["first", "a.1.0.0", "a.1.0.1", "b.2.0.0", "b.2.0.1", "a.3.0.0", "a.3.0.1", "after", "z"]
    assert list(jobs[True].res["gru"]) == list(jobs[False].res["gru"]) == keys
    assert jobs[True].res["gru"] == jobs[False].res["gru"]
    split, whole = jobs[True].stored["toy.parquet"], jobs[False].stored["toy.parquet"]
    pd.testing.assert_frame_equal(split.drop(columns="pid"), whole.drop(columns="pid"))
    if cpus is None and (os.cpu_count() or 1) > 1:  # each piece in a fresh process of its own
        assert split["pid"].nunique() == 3 and os.getpid() not in set(split["pid"])
    if cpus == 1:
        assert set(split["pid"]) == {os.getpid()}


def test_a_later_step_reading_a_split_sweeps_keys_is_refused(tmp_path):
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    with pytest.raises(RuntimeError, match=r"step 1 reads res gru .* which .*_plan"):
        job.run_steps([job.split(_plan), lambda: job.res["gru"].get("a.1.0.0")])


def _ex39_job(tmp_path: Path) -> SimpleNamespace:
    published = pd.DataFrame({"kind": ["capture", "capture", "boundary"], "instance_id": ["t0", "t1", "t0"],
                              "x_hole": [1.0, -2.0, 1.0], "c": [1.0, 0.5, 1.0], "ratio": [1.0, 1.0, np.nan],
                              "engine": "pybullet"})
    (tmp_path / "engines" / "results").mkdir(parents=True)
    published.to_parquet(tmp_path / "engines" / "results" / "engine_scans.parquet")
    return SimpleNamespace(root=tmp_path, quick=True, cfg={"ex39_truths_quick": 1}, progress=lambda *a: None,
                           p=SimpleNamespace(scan={"step": 0.1}, noise_sigma=0.5), stored={}, res=defaultdict(dict))


def test_ex39s_pieces_are_its_grid_points_in_grid_order_softest_submitted_first(monkeypatch, tmp_path):
    """The combined rows equal the one-process sweep's (``sweep`` then the published rows), row for row, whether
    each point is a piece (full) or all of them one (quick)."""
    def fake(truths, k, z, scan, sigma):
        rows = truths.assign(kind="capture", ratio=1.0 if np.isnan(k) else 1.0 + 100.0 / k, side="left")
        return rows.rename(columns={"true_x_hole": "x_hole", "true_c": "c"}).assign(engine="pybullet"), 0.0

    monkeypatch.setattr(ex39, "point_rows", fake)
    monkeypatch.setattr(ex39, "summary", lambda rows: {"n": len(rows)})
    quick = _ex39_job(tmp_path)
    full = SimpleNamespace(**{**vars(quick), "quick": False, "cfg": {"ex39_truths": 1}, "res": defaultdict(dict)})
    cut = ex39.pieces(full)
    assert [args[1] for _, args in cut.calls] == [(i,) for i in range(13)]
    assert [ex39.grid()[i][0] for i in cut.order()[:2]] == ["k300_z010", "k300_z100"] and cut.order()[-1] == 0
    assert [args[1] for _, args in ex39.pieces(quick).calls] == [tuple(range(13))]
    published = pd.read_parquet(tmp_path / "engines" / "results" / "engine_scans.parquet")
    truths = ex39.published_truths(published, 1)
    mine = published[published["instance_id"].isin(truths["instance_id"])].drop(columns="engine")
    whole = pd.concat([ex39.sweep(truths, quick.p.scan, 0.5), mine.assign(point=ex39.PUBLISHED, index=-1)],
                      ignore_index=True)
    for job in (quick, full):
        job.stored = {}
        in_place(job, ex39.pieces)
        pd.testing.assert_frame_equal(job.stored[ex39.STORED], whole)
        assert job.res[ex39.GROUP] == {"n": len(whole)}


def test_ex38s_pieces_are_its_arms_the_bisection_with_its_grid(monkeypatch):
    job = SimpleNamespace(quick=False, cfg={"ex38_truths": 2}, p="protocol", progress=lambda *a: None)
    monkeypatch.setattr("importlib.util.find_spec", lambda name: object())
    cut = ex38.pieces(job)
    assert [args[1:] for _, args in cut.calls] == [(arm, grid, 2, True) for arm, grid in ex38.GRIDS.items()]
    assert cut.order() == [0, 1]  # contact offset: 8 points and its bisections at most; rest offset: 6 and its
    parts = [pd.DataFrame({"arm": [arm], "value": [1.0]}) for arm in ex38.GRIDS]
    monkeypatch.setattr(ex38, "summary", lambda rows: {"n": len(rows)})
    assert cut.combine(parts)["stored"][ex38.STORED]["arm"].tolist() == list(ex38.GRIDS)
    assert ex38.pieces(SimpleNamespace(**{**vars(job), "cfg": {"ex38_truths": -1}})) is None
