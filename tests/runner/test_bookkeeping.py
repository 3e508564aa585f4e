"""The run's per-unit bookkeeping, made cheaper for issue 42, gives what the plain forms give."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.runner import study
from probecommit.runner.instances import InstanceTable
from probecommit.runner.study import run_study, unit_names
from probecommit.store import rundir
from probecommit.store.rundir import RunDir

_IDS = st.sampled_from([f"s-{i}" for i in (0, 1, 2, 9, 10, 99, 100, 9999, 10000)])


@settings(max_examples=60, deadline=None)
@given(order=st.lists(_IDS, unique=True, max_size=6), rows=st.lists(_IDS, min_size=1, max_size=30),
       as_object=st.booleans())
def test_instance_positions_are_each_ids_place_in_the_order_and_unknown_ids_come_last(order, rows, as_object):
    positions = {iid: n for n, iid in enumerate(order)}
    column = pd.Series(rows, dtype=object if as_object else "str")
    got = rundir._instance_positions(pd.DataFrame({"instance_id": column}), positions)
    expected = [float(positions.get(iid, len(positions))) for iid in rows]  # the definition, row by row
    assert got.dtype == np.float64
    assert got.tolist() == expected


@pytest.mark.parametrize("done", [(), ("unit-00001",), ("unit-00000", "unit-00003", "unit-00004")],
                         ids=["fresh", "a gap", "gaps at both ends"])
@pytest.mark.parametrize("parallel", [1, 2])
def test_a_groups_instances_are_its_units_rows_whether_sliced_or_gathered(done, parallel):
    instances = pd.DataFrame({"instance_id": [f"t-{i}" for i in range(11)], "instance_index": np.arange(11),
                              "true_x": np.linspace(0.0, 1.0, 11)})
    todo = [(name, sl) for name, sl in unit_names(len(instances), 2) if name not in done]
    jobs = study._groups(None, InstanceTable.of(instances), todo, repeats=3, parallel=parallel)
    assert [unit for _, _, units in jobs for unit, _ in units] == [name for name, _ in todo]
    at = 0
    for _, frame, units in jobs:
        rows = np.concatenate([np.arange(sl.start, sl.stop) for _, sl in todo[at:at + len(units)]])
        pd.testing.assert_frame_equal(frame.to_frame(), instances.iloc[rows].reset_index(drop=True), check_exact=True)
        assert [n for _, n in units] == [sl.stop - sl.start for _, sl in todo[at:at + len(units)]]
        at += len(units)


def test_kept_units_are_counted_at_their_tables_bytes(tmp_path, make_config, monkeypatch):
    """A unit's size measured when it is queued is the size it is kept at (a run's units held for
    the merge stay within ``KEEP_WRITTEN_BYTES`` by this count)."""
    seen = []
    keep = RunDir._keep

    def checked(self, unit, tables, size=None):
        actual = sum(t.nbytes for t in tables.values())
        assert size is None or size == actual
        seen.append(size)
        keep(self, unit, tables, size)
        assert self._kept_bytes == sum(t.nbytes for kept in self._kept.values() for t in kept.values())

    monkeypatch.setattr(RunDir, "_keep", checked)
    result = run_study(make_config(unit_instances=2), tmp_path / "run", threads=1)
    assert seen and all(size is not None for size in seen)  # every unit measured once, when queued
    assert len(seen) == result.manifest["units"]


@pytest.mark.parametrize("faulty", [False, True], ids=["clean", "failed rows"])
def test_a_runs_episodes_equal_reading_its_file(tmp_path, make_config, monkeypatch, faulty):
    """``run_study``'s episodes come from the table it wrote, not a read of the file: the same
    frame (values, dtypes, column order), with failed rollouts' and commits' rows too."""
    cfg = make_config(repeats=4, methods=["blind_bayes", "blind_robust", "probe_robust"])
    if faulty:
        from tests.runner.faults import inject, pick_faults

        clean = run_study(cfg, tmp_path / "clean", threads=1)
        inject(monkeypatch, **pick_faults(clean.run_dir)["faults"])
    result = run_study(cfg, tmp_path / "run", threads=1)
    assert (result.failed_episodes > 0) == faulty
    read = pd.read_parquet(result.run_dir / "episodes.parquet")
    pd.testing.assert_frame_equal(result.episodes, read, check_exact=True)
    assert list(result.episodes.dtypes) == list(read.dtypes)
    # A complete run opened again reads its file: the same frame.
    again = run_study(cfg, tmp_path / "run", threads=1)
    pd.testing.assert_frame_equal(again.episodes, read, check_exact=True)


@settings(max_examples=60, deadline=None)
@given(n_units=st.integers(1, 300), unit_instances=st.integers(1, 9), repeats=st.integers(1, 8),
       parallel=st.integers(1, 4))
def test_groups_are_as_many_as_the_episode_bound_needs_and_differ_by_one_unit_at_most(n_units, unit_instances, repeats,
                                                                                     parallel):
    """Every group holds at most GROUP_EPISODES episodes' worth of units (and, in parallel, a quarter of the
    units per worker at most), no more groups are made than that bound needs, and their sizes differ by
    one unit at most: threads taking groups in turn finish together."""
    import math

    instances = pd.DataFrame({"instance_id": [f"t-{i}" for i in range(n_units * unit_instances)],
                              "instance_index": np.arange(n_units * unit_instances)})
    todo = unit_names(len(instances), unit_instances)
    bound = max(1, study.GROUP_EPISODES // (unit_instances * repeats))
    if parallel > 1:
        bound = max(1, min(bound, math.ceil(n_units / (2 * parallel))))
    sizes = [len(units) for _, _, units in study._groups(None, instances, todo, repeats, parallel)]
    assert sum(sizes) == n_units and max(sizes) <= bound
    assert len(sizes) == math.ceil(n_units / bound)
    assert max(sizes) - min(sizes) <= 1
