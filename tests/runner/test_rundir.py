"""A run directory of another version or config is refused, with a message saying why."""

import json

import pytest

from probecommit import __version__
from probecommit.runner.config import dump_config
from probecommit.runner.study import run_study
from probecommit.store.rundir import RunDir, RunDirError


def test_other_config_is_refused_naming_the_field(tmp_path, make_config):
    run_study(make_config(), tmp_path / "run")
    with pytest.raises(RunDirError, match=r"different config \(seed is 11 there, 12 here\)") as err:
        run_study(make_config(seed=12), tmp_path / "run")
    assert "\n" not in str(err.value)


def test_other_config_is_refused_while_in_progress(tmp_path, make_config):
    run = RunDir(tmp_path / "run")
    run.prepare(dump_config(make_config()))
    with pytest.raises(RunDirError, match=r"belief\.particles is 256 there, 128 here"):
        run_study(make_config(belief={"particles": 128}), tmp_path / "run")


def test_manifest_of_another_version_is_refused(tmp_path, make_config):
    out = run_study(make_config(), tmp_path / "run").run_dir
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["probecommit_version"] = "0.0.1"
    (out / "manifest.json").write_text(json.dumps(manifest))
    (out / "shards" / "VERSION").unlink()  # e.g. shards cleaned up after completion
    with pytest.raises(RunDirError, match=rf"written by probecommit 0\.0\.1, this is {__version__}"):
        run_study(make_config(), out)


def test_unfinished_run_of_another_version_is_refused(tmp_path, make_config):
    out = run_study(make_config(), tmp_path / "run").run_dir
    (out / "manifest.json").unlink()
    (out / "shards" / "VERSION").write_text("0.0.1")
    with pytest.raises(RunDirError, match=rf"started by probecommit 0\.0\.1, this is {__version__}"):
        run_study(make_config(), out)


def test_version_is_reported_before_a_config_difference(tmp_path, make_config):
    # A new version may change config defaults too; the version is the real reason.
    out = run_study(make_config(), tmp_path / "run").run_dir
    (out / "shards" / "VERSION").write_text("0.0.1")
    with pytest.raises(RunDirError, match="started by probecommit 0.0.1"):
        run_study(make_config(seed=99), out)


def test_corrupt_manifest_is_refused(tmp_path, make_config):
    out = run_study(make_config(), tmp_path / "run").run_dir
    (out / "manifest.json").write_text("{not json")
    with pytest.raises(RunDirError, match="not valid JSON"):
        run_study(make_config(), out)


def test_foreign_directory_is_refused_and_left_untouched(tmp_path, make_config):
    foreign = tmp_path / "photos"
    foreign.mkdir()
    (foreign / "cat.jpg").write_bytes(b"x")
    with pytest.raises(RunDirError, match="not a probecommit run directory"):
        run_study(make_config(), foreign)
    assert [p.name for p in foreign.iterdir()] == ["cat.jpg"]
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(RunDirError, match="not a directory"):
        run_study(make_config(), afile)


def test_canonical_order_follows_the_instances_not_the_id_text():
    import pandas as pd

    from probecommit.store.rundir import canonical_tables

    ids = ["s-9999", "s-10000"]
    frames = {
        "instances": pd.DataFrame({"instance_id": ids[::-1], "split": "s", "instance_index": [10000, 9999]}),
        "probes": pd.DataFrame({"instance_id": ["s-10000", "s-9999", "s-9999"], "repeat": [0, 0, 0],
                                "j": [1, 2, 1], "u": [0.0, 1.0, 2.0], "y": [0.0, 0.0, 0.0]}),
        "episodes": pd.DataFrame({"instance_id": ["s-10000", "s-9999", "s-9999"], "repeat": [0, 1, 0],
                                  "k": [0, 0, 0], "method": ["a", "b", "c"]}),
        "engine_cache": pd.DataFrame({"engine": "e", "query": ["t", "p", "t"], "x_hole": [2.0, 1.0, 1.0],
                                      "c": 1.0, "arg": [[0.0], [3.0], [1.0]], "value": [[0.0], [0.0], [0.0]]}),
    }
    out = canonical_tables(frames)
    assert out["instances"]["instance_id"].tolist() == ids
    assert out["probes"][["instance_id", "j"]].values.tolist() == [["s-9999", 1], ["s-9999", 2], ["s-10000", 1]]
    assert out["episodes"]["method"].tolist() == ["c", "b", "a"]
    assert out["engine_cache"][["x_hole", "query"]].values.tolist() == [[1.0, "p"], [1.0, "t"], [2.0, "t"]]


@pytest.mark.parametrize("args", [
    [[1.0, 2.0], [1.0, -1.0], [0.5, 9.0], [1.0, 2.0]],  # one length: one column per component
    [[1.0, 2.0], [1.0], [0.5, 9.0, 1.0], [1.0, 2.0, -3.0]],  # lengths differ: tuples
])
def test_engine_cache_arguments_sort_as_tuples(args):
    import pandas as pd

    from probecommit.store.rundir import canonical_tables

    frame = pd.DataFrame({"engine": "e", "query": "q", "x": 0.0, "arg": args, "value": [[float(i)] for i in range(4)]})
    out = canonical_tables({"engine_cache": frame})["engine_cache"]
    expected = sorted(range(4), key=lambda i: tuple(args[i]))  # stable: equal arguments keep their order
    assert out["value"].map(lambda v: int(v[0])).tolist() == expected
    assert list(out.columns) == list(frame.columns)
    # The same order from the Arrow table (a replay's answers), its arguments read from the list buffers.
    import pyarrow as pa

    from probecommit.store.rundir import engine_cache_order

    assert engine_cache_order(pa.Table.from_pandas(frame, preserve_index=False)).tolist() == expected


def test_the_merge_of_kept_shard_tables_equals_the_merge_of_the_files(tmp_path, monkeypatch, make_config):
    from tests.runner.faults import inject, pick_faults

    cfg = make_config(repeats=4, methods=["blind_bayes", "blind_robust", "probe_robust"])
    clean = run_study(cfg, tmp_path / "clean", threads=1)
    inject(monkeypatch, **pick_faults(clean.run_dir)["faults"])  # failed rollouts and commits: rows of every kind
    kept = run_study(cfg, tmp_path / "kept", threads=1)
    monkeypatch.setattr(RunDir, "KEEP_WRITTEN_BYTES", 0)  # every shard read back from its file
    read = run_study(cfg, tmp_path / "read", threads=1)
    assert kept.failed_episodes > 0
    assert kept.manifest["sha256"] == read.manifest["sha256"]


def test_manifest_engine_versions_are_the_installed_distributions():
    from importlib import metadata

    from probecommit.store.rundir import engine_versions

    versions = engine_versions()
    for name in ("numpy", "pandas", "pyarrow"):
        assert versions[name] == metadata.version(name)
    assert set(versions) >= {"python", "mujoco", "pybullet", "sapien", "ray", "numba"}


def test_the_package_version_is_read_on_first_use_from_the_distribution():
    import subprocess
    import sys
    from importlib import metadata

    code = "import probecommit; v = probecommit.__version__; from probecommit import __version__ as w; print(v == w, v)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", metadata.version("probecommit")]


def test_merged_tables_equal_concatenating_each_table_converted_by_pandas(tmp_path):
    """Tables of one schema are joined as Arrow tables and converted once; tables whose columns
    differ, and empty ones, are joined as pandas joins each table converted alone."""
    import pandas as pd
    import pyarrow as pa

    from probecommit.store.rundir import merge_tables

    full = pd.DataFrame({"instance_id": ["a", "b"], "repeat": [0, 1], "realized": [0.0, 1.0], "status": ["ok", "ok"]})
    frames = {"u0": full, "u1": full.iloc[:0], "u2": full.assign(instance_id=["c", "d"]),
              "u3": pd.DataFrame({"instance_id": ["e"], "repeat": [0], "status": ["failed"]})}  # fewer columns
    tables = {u: pa.Table.from_pandas(f, preserve_index=False) for u, f in frames.items()}
    alone = {u: t.to_pandas() for u, t in tables.items()}
    expected = pd.concat([alone[u] for u in ("u0", "u2", "u3")], ignore_index=True)
    pd.testing.assert_frame_equal(merge_tables(list(tables.values())), expected)
    same = pd.concat([alone[u] for u in ("u0", "u2")], ignore_index=True)
    pd.testing.assert_frame_equal(merge_tables([tables[u] for u in ("u0", "u1", "u2")]), same)
    pd.testing.assert_frame_equal(merge_tables([tables["u1"]]), alone["u1"])


def _episode_rows(ids_repeats, vector, k=(1, 2)):
    """Episode rows of (instance, repeat) trajectories at budgets ``k``, every column filled; a
    ``vector`` action is two columns, action_0 and action_1."""
    import numpy as np
    import pandas as pd

    rows = [(i, r, kk) for i, r in ids_repeats for kk in k]
    n = len(rows)
    values = np.arange(n, dtype=float)
    actions = {"action_0": values, "action_1": -values} if vector else {"action": values}
    return pd.DataFrame({"instance_id": [r[0] for r in rows], "repeat": [r[1] for r in rows], "k": [r[2] for r in rows],
                         "method": "probe_robust", "variant": "v", **actions, "predicted": values / n,
                         "realized": 0.0, "z_true": values, "retained_lo": -1.0, "retained_hi": 1.0, "hull_lo": -2.0,
                         "hull_hi": 2.0, "covered": True, "escaped": False, "score_s": 0.5, "post_var": 1.0,
                         "max_surprise": 2.0, "n_retained": np.arange(n), "belief_resets": 0, "status": "ok",
                         "error": ""})


@pytest.mark.parametrize("vector", [False, True])
def test_episodes_streamed_in_parts_equal_the_merged_table(tmp_path, vector):
    """Parts in instance order, with failed-rollout rows (fewer columns) placed among them, read
    back as the table ``finalize`` writes of all the rows at once: same rows, order, columns
    (the components of a vector action, not an empty ``action``) and dtypes."""
    import pandas as pd

    from probecommit.store.rundir import atomic_write_parquet, canonical_tables
    from probecommit.store.schema import EPISODE_COLUMNS

    ids = [f"s-{n}" for n in (7, 8, 9, 10, 11, 12)]
    instances = pd.DataFrame({"instance_id": ids, "split": "s", "instance_index": [7, 8, 9, 10, 11, 12]})
    # s-7 and s-11 failed in every repeat (in no part), s-9 in one; "zz" is in no instances table.
    failed = pd.DataFrame({"instance_id": ["s-11", "zz", "s-9", "s-7", "s-7", "s-11"], "repeat": [0, 0, 1, 0, 1, 1],
                           "k": 0, "method": "rollout", "variant": "v", "status": "failed",
                           "error": ["nan", "nan", "raised", "nan", "nan", "nan"]})
    parts = [_episode_rows([("s-8", 0), ("s-8", 1), ("s-9", 0)], vector), _episode_rows([("s-10", 0), ("s-10", 1)], vector),
             _episode_rows([("s-12", 1), ("s-12", 0)], vector)]
    run = RunDir(tmp_path / "run")
    run.shards.mkdir(parents=True)
    stream = run.episode_stream(instances, failed)
    for part in parts:
        stream.add(part)
    stream.finish()
    merged = canonical_tables({"instances": instances, "episodes": pd.concat(parts + [failed], ignore_index=True)})
    atomic_write_parquet(tmp_path / "merged.parquet", merged["episodes"], EPISODE_COLUMNS)
    expected = pd.read_parquet(tmp_path / "merged.parquet")
    got = pd.read_parquet(run.table_path("episodes"))
    pd.testing.assert_frame_equal(got, expected, check_exact=True)
    assert got["n_retained"].dtype == "float64" and got["instance_id"].iloc[0] == "s-7"  # promoted as by the merge
    assert not list(run.shards.iterdir())  # the parts went

    # A part out of order is refused, and a block that raises leaves no part behind (nor a table).
    run.table_path("episodes").unlink()
    with pytest.raises(ValueError, match="instance order"), run.episode_stream(instances) as stream:
        stream.add(parts[1])
        stream.add(parts[0])
    assert not list(run.shards.iterdir()) and not run.table_path("episodes").exists()


def _pandas_route(columns, n_rows, schema=()):
    import pandas as pd

    from probecommit.store.rundir import arrow_table

    return arrow_table(pd.DataFrame(columns), schema)


@pytest.mark.parametrize("case", ["numbers", "strings", "scalars", "lists", "empty", "nulls"])
def test_tables_built_from_columns_equal_those_built_through_pandas(case):
    """Same types, values (NaN as null) and pandas metadata as ``arrow_table(pd.DataFrame(columns))``."""
    import numpy as np

    from probecommit.store.rundir import arrow_from_columns
    from probecommit.store.schema import EPISODE_COLUMNS, PROBE_COLUMNS

    n = 3
    cases = {
        "numbers": ({"instance_id": np.array(["a", "b", "c"]), "repeat": np.arange(n), "j": np.arange(n, dtype=np.int64),
                     "u_0": np.array([0.5, np.nan, 2.0]), "y_0": np.array([1.0, 2.0, -np.inf])}, PROBE_COLUMNS),
        "strings": ({"instance_id": np.array(["a", "b", "c"], dtype=object), "k": np.array([1, 2, 3]),
                     "status": np.array(["ok", "failed", "ok"], dtype=object), "covered": np.array([True, False, True]),
                     "n_retained": np.array([1, 2, 3], dtype=np.int64)}, EPISODE_COLUMNS),
        "scalars": ({"instance_id": np.array(["a", "b", "c"]), "repeat": np.arange(n, dtype=np.int64),
                     "k": np.int64(0), "method": "rollout", "status": "failed", "error": np.array(["x", "y", "z"])},
                    EPISODE_COLUMNS),
        "lists": ({"engine": ["analytic"] * n, "query": ["tap", "tap", "aim"], "x_hole": [0.5, None, 1.0],
                   "c": [1.0, 1.1, 1.2], "arg": [[0.0], [1.0], [2.0, 3.0]], "value": [[1.0], [2.0], [3.0]]}, ()),
        "empty": ({"engine": [], "query": [], "x_hole": [], "arg": [], "value": []}, ()),
        "nulls": ({"instance_id": np.array(["a", "b", "c"]), "hull_lo": np.array([None, None, None], dtype=object),
                   "max_surprise": np.full(n, np.nan)}, EPISODE_COLUMNS),
    }
    columns, schema = cases[case]
    rows = 0 if case == "empty" else n
    built = arrow_from_columns(columns, rows, schema)
    expected = _pandas_route(columns, rows, schema)
    assert built.equals(expected, check_metadata=True), (built.schema, expected.schema)
    assert built.to_pandas().equals(expected.to_pandas())


@pytest.mark.parametrize("family", ["insertion", "planar_slide"], ids=["insertion", "vector actions"])
def test_a_units_tables_equal_those_built_through_pandas(monkeypatch, family):
    from probecommit.runner import study
    from probecommit.runner.build import build_model
    from probecommit.runner.config import parse_config
    from probecommit.runner.instances import draw_instances

    contexts = {"contexts": [[1.0, 0.2], [0.6, -0.3]]} if family == "planar_slide" else {}
    config = parse_config({"name": "cols", "task": family, "seed": 3, "repeats": 2, "probes": {"budget": 3},
                           "instances": {"split": "t", "count": 2, "seed": 1, **contexts}, "belief": {"particles": 64},
                           "simulator": {"engine": "analytic"}, "blind_prior_samples": 200})
    instances = draw_instances(config, build_model(config))
    data = config.model_dump(mode="json")
    _, built, _ = study.compute_unit(data, instances, "unit-00000")
    monkeypatch.setattr(study, "arrow_from_columns", _pandas_route)
    _, expected, _ = study.compute_unit(data, instances, "unit-00000")
    for name in built:
        assert built[name].equals(expected[name], check_metadata=True), name


def test_run_files_and_result_files_refuse_a_planted_symlink_by_one_rule(tmp_path):
    """Run files (``rundir.atomic_write_bytes``) and result files (``safefile.write_bytes``) are
    written by the same ``safefile.atomic_file``: a symlink at the path is never followed."""
    from probecommit.store.rundir import atomic_write_bytes
    from probecommit.store.safefile import UnsafePathError, write_bytes

    target = tmp_path / "elsewhere.txt"
    target.write_bytes(b"keep")
    for write in (atomic_write_bytes, write_bytes):
        link = tmp_path / f"{write.__name__}.parquet"
        link.symlink_to(target)
        with pytest.raises(UnsafePathError):
            write(link, b"new")
        assert target.read_bytes() == b"keep" and link.is_symlink()
        assert not list(tmp_path.glob(".*.tmp"))  # nothing left behind
