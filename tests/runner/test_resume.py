"""Killed runs resume: finished units are kept, partial ones redone, tables identical."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
import yaml

import probecommit.store.rundir as rundir
from probecommit.runner import study
from probecommit.runner.config import load_config
from probecommit.runner.study import run_study
from probecommit.store.rundir import RunDir, RunDirError

TABLES = ("instances", "probes", "episodes", "engine_cache")


def assert_same_tables(a: Path, b: Path) -> None:
    """Byte-identical final tables (and so identical manifest digests)."""
    for name in TABLES:
        fa, fb = a / f"{name}.parquet", b / f"{name}.parquet"
        if fa.read_bytes() != fb.read_bytes():
            pd.testing.assert_frame_equal(pd.read_parquet(fa), pd.read_parquet(fb), check_exact=True)
            raise AssertionError(f"{name}.parquet: equal frames but different bytes")


def tiny(make_config):
    return make_config(
        instances={"count": 4}, probes={"budget": 3}, belief={"particles": 32},
        unit_instances=2, blind_prior_samples=200,
    )


class Killed(BaseException):
    """Stands in for SIGKILL: not an Exception, so nothing in the runner catches it."""


def test_killed_at_every_write_resumes_to_identical_tables(tmp_path, make_config, monkeypatch):
    cfg = tiny(make_config)
    monkeypatch.setattr(RunDir, "batch_units", 1)  # a batch per unit: a kill between any two units
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    real_write = rundir.atomic_write_bytes
    writes = []

    def counting(path, data):
        writes.append(path.name)
        real_write(path, data)

    monkeypatch.setattr(rundir, "atomic_write_bytes", counting)
    reference = run_study(cfg, tmp_path / "ref").run_dir
    monkeypatch.setattr(rundir, "atomic_write_bytes", real_write)
    # VERSION, CODE, config, 2 batches of one unit (one durable write each), 4 tables, manifest.
    assert len(writes) == 3 + 2 + 4 + 1 and writes[-1] == "manifest.json"

    for n in range(len(writes)):
        calls = {"n": 0}

        def dying(path, data, n=n):
            if calls["n"] == n:
                # Die mid-write: half the bytes in a temporary that is never renamed.
                tmp = path.parent / f".{path.name}.killed.tmp"
                tmp.write_bytes(data[: len(data) // 2])
                raise Killed(path.name)
            calls["n"] += 1
            real_write(path, data)

        out = tmp_path / f"killed-{n}"
        monkeypatch.setattr(rundir, "atomic_write_bytes", dying)
        with pytest.raises(Killed):
            run_study(cfg, out)
        assert not (out / "manifest.json").is_file()
        monkeypatch.setattr(rundir, "atomic_write_bytes", real_write)
        result = run_study(cfg, out)
        assert_same_tables(reference, out)
        assert not list(out.glob("**/*.tmp")), f"temporaries left after resuming a kill at write {n}"
        assert result.manifest["resumed_units"] == sum(1 for w in writes[:n] if w.startswith("batch-"))


def test_units_are_group_committed_one_durable_write_per_batch(tmp_path, make_config, monkeypatch):
    """Six units in batches of four: two batch files, each one fsynced write plus an fsync of
    shards/ (not five files a unit); the tables equal those of a batch per unit."""
    cfg = make_config(unit_instances=1)  # 6 instances: 6 units
    monkeypatch.setattr(RunDir, "batch_units", 1)
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)  # each unit computed alone
    reference = run_study(cfg, tmp_path / "ref").run_dir
    assert len(list((reference / "shards").glob("batch-*.pcb"))) == 6
    monkeypatch.setattr(RunDir, "batch_units", 4)
    monkeypatch.setattr(RunDir, "batch_seconds", 1e9)
    fsyncs = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (fsyncs.append(fd), real_fsync(fd))[1])
    out = run_study(cfg, tmp_path / "run").run_dir
    assert sorted(p.name for p in (out / "shards").glob("batch-*")) == ["batch-000000.pcb", "batch-000001.pcb"]
    # VERSION, CODE, config: 3; batches: 2 x (file + directory); 4 tables and the manifest: 5.
    assert len(fsyncs) == 3 + 2 * 2 + 5
    assert_same_tables(reference, out)


@pytest.mark.parametrize("damage", ["garbage", "cut", "flipped", "deleted"])
def test_a_damaged_batch_is_redone_and_the_others_are_kept(tmp_path, make_config, monkeypatch, damage):
    monkeypatch.setattr(RunDir, "batch_units", 1)
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    cfg = make_config()  # 6 instances, 2 per unit: 3 units, a batch each
    reference = run_study(cfg, tmp_path / "ref").run_dir
    out = run_study(cfg, tmp_path / "run").run_dir
    shards = out / "shards"
    (out / "manifest.json").unlink()
    (out / "episodes.parquet").unlink()
    bad = shards / "batch-000001.pcb"
    data = bad.read_bytes()
    if damage == "garbage":
        bad.write_bytes(b"not a batch")
    elif damage == "cut":
        bad.write_bytes(data[:-10])
    elif damage == "flipped":  # one payload byte altered: the payload's sha256 catches it
        bad.write_bytes(data[:-5] + bytes([data[-5] ^ 1]) + data[-4:])
    else:
        bad.unlink()
    kept = {p.name: p.stat().st_mtime_ns for p in shards.glob("batch-00000[02].pcb")}
    time.sleep(0.01)
    result = run_study(cfg, out)
    assert result.manifest["resumed_units"] == 2
    assert {p.name: p.stat().st_mtime_ns for p in shards.glob("batch-00000[02].pcb")} == kept
    assert_same_tables(reference, out)


def test_a_unit_in_no_batch_counts_as_not_done(tmp_path, make_config, monkeypatch):
    monkeypatch.setattr(RunDir, "batch_units", 1)
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    out = run_study(make_config(), tmp_path / "run").run_dir
    run = RunDir(out)
    assert run.unit_done("unit-00000")
    run._batches["unit-00000"].unlink()  # the batch holding it (threads finish in any order)
    assert not run.unit_done("unit-00000") and run.unit_done("unit-00001")


def test_rerunning_a_complete_run_changes_nothing(tmp_path, make_config):
    first = run_study(make_config(), tmp_path / "run")
    manifest = (first.run_dir / "manifest.json").read_bytes()
    again = run_study(make_config(), tmp_path / "run")
    assert (first.run_dir / "manifest.json").read_bytes() == manifest
    pd.testing.assert_frame_equal(again.episodes, first.episodes, check_exact=True)


def test_a_directory_being_written_is_refused(tmp_path, make_config):
    cfg = make_config()
    run_study(cfg, tmp_path / "run")
    (tmp_path / "run" / "manifest.json").unlink()  # unfinished: a second writer would race
    with RunDir(tmp_path / "run").lock():
        with pytest.raises(RunDirError, match="being written by another probecommit process"):
            run_study(cfg, tmp_path / "run")


KILL_CONFIG = {
    "name": "killme",
    "seed": 5,
    "repeats": 4,
    "instances": {"split": "kill", "count": 24, "seed": 1},
    "probes": {"budget": 8},
    "belief": {"particles": 4096},
    "simulator": {"engine": "analytic"},
    "unit_instances": 1,
    "blind_prior_samples": 2000,
}


@pytest.mark.slow
def test_sigkilled_cli_run_resumes_to_identical_tables(tmp_path):
    path = tmp_path / "kill.yaml"
    path.write_text(yaml.safe_dump(KILL_CONFIG))
    out = tmp_path / "run"
    script = Path(sys.executable).with_name("probecommit")
    entry = [str(script)] if script.is_file() else [sys.executable, "-m", "probecommit.cli.app"]
    cmd = entry + ["run", str(path), "--out", str(out)]
    env = {**os.environ, "COLUMNS": "120", "PROBECOMMIT_BATCH_UNITS": "1",
           "PROBECOMMIT_GROUP_EPISODES": "1"}
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    deadline = time.monotonic() + 30
    done = []
    while time.monotonic() < deadline and proc.poll() is None:
        done = list((out / "shards").glob("batch-*.pcb"))
        if len(done) >= 3:
            break
        time.sleep(0.005)
    assert proc.poll() is None, f"run finished before it could be killed: {proc.stderr.read().decode()[-500:]}"
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    proc.stderr.close()
    assert proc.returncode == -signal.SIGKILL
    assert not (out / "manifest.json").exists()
    units_done = len(RunDir(out).done_units())
    assert 3 <= units_done < 24

    again = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=60)
    assert again.returncode == 0, again.stderr
    manifest = RunDir(out).manifest()
    assert manifest["resumed_units"] == units_done

    # Reference: uninterrupted, in one unit (grouping must not matter either).
    ref_cfg = load_config(path).model_copy(update={"unit_instances": 24})
    reference = run_study(ref_cfg, tmp_path / "ref").run_dir
    assert_same_tables(reference, out)
    tables = lambda m: {k: v for k, v in m["sha256"].items() if k.endswith(".parquet")}  # noqa: E731 - configs differ in unit_instances
    assert tables(manifest) == tables(RunDir(reference).manifest())


def test_a_resumed_run_decodes_each_stored_batch_once(tmp_path, make_config, monkeypatch):
    """On resume ``done_units`` decodes every batch to check it; the merge then uses those tables
    instead of decoding the batches a second time (within ``KEEP_WRITTEN_BYTES``)."""
    from probecommit.store import batches

    cfg = tiny(make_config)
    monkeypatch.setattr(RunDir, "batch_units", 1)
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    reference = run_study(cfg, tmp_path / "ref").run_dir
    run = tmp_path / "resumed"
    run_study(cfg, run)
    for name in (*TABLES, "manifest"):  # killed after the last batch, before the merge
        for path in run.glob(f"{name}.*"):
            path.unlink()
    real_read, reads = batches.read, []

    def counting(path):
        reads.append(Path(path).name)
        return real_read(path)

    monkeypatch.setattr(batches, "read", counting)
    run_study(cfg, run)
    assert reads and len(reads) == len(set(reads)), reads
    assert_same_tables(reference, run)
