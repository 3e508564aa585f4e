"""An unfinished run is resumed only by the code that started it (same version is not enough)."""

from __future__ import annotations

import pytest

from probecommit.runner.study import run_study
from probecommit.store.rundir import CODE, MANIFEST, RunDirError, code_identity
from tests.conftest import small_config


def _unfinished(tmp_path):
    config = small_config(name="ident", instances={"count": 4})
    out = tmp_path / "run"
    run_study(config, out)
    (out / MANIFEST).unlink()  # as if killed before the merge
    return config, out


def test_resume_with_the_same_code_finishes(tmp_path):
    config, out = _unfinished(tmp_path)
    assert (out / "shards" / CODE).read_text() == code_identity()
    result = run_study(config, out)
    assert result.manifest["code_sha256"] == code_identity() and "git_dirty" in result.manifest


def test_resume_after_a_code_change_is_refused_with_the_fresh_start_command(tmp_path):
    config, out = _unfinished(tmp_path)
    (out / "shards" / CODE).write_text("0" * 64)  # started by another build of the same version
    with pytest.raises(RunDirError, match=r"unfinished run started by other code .* delete .* and rerun the same command"):
        run_study(config, out)


# ---- provenance per shard: every batch carries the code that wrote it (issue 38, item 1) ----

def _complete(tmp_path, monkeypatch):
    from probecommit.runner import study
    from probecommit.store.rundir import RunDir

    monkeypatch.setattr(RunDir, "batch_units", 1)  # a batch per unit, as after a run killed often
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    config = small_config(name="prov", instances={"count": 4})
    out = tmp_path / "run"
    return config, out, run_study(config, out)


def _other_code(monkeypatch):
    import probecommit.store.rundir as rundir

    before = code_identity()
    monkeypatch.setattr(rundir, "_CODE_IDENTITY", "f" * 64)  # the package's source changed
    return before


def test_every_batch_carries_the_identity_the_manifest_records(tmp_path, monkeypatch):
    from probecommit.store import batches

    _, out, result = _complete(tmp_path, monkeypatch)
    found = sorted((out / "shards").glob("batch-*.pcb"))
    assert len(found) == 2
    assert {batches.read_header(p)["code"] for p in found} == {result.manifest["code_sha256"]} == {code_identity()}


def test_resume_after_deleting_a_batch_and_changing_the_code_is_refused_naming_both(tmp_path, monkeypatch):
    """The issue's scenario: one unit's shards and episodes.parquet of a complete run deleted, the
    code changed, rerun. Refused (one line, both identities), nothing rewritten: no mixed table."""
    config, out, _ = _complete(tmp_path, monkeypatch)
    (out / "shards" / "batch-000001.pcb").unlink()
    (out / "episodes.parquet").unlink()
    manifest = (out / MANIFEST).read_bytes()
    old = _other_code(monkeypatch)
    with pytest.raises(RunDirError) as err:
        run_study(config, out)
    message = str(err.value)
    assert "\n" not in message and old[:12] in message and "f" * 12 in message and "batch-000000.pcb" in message
    assert (out / MANIFEST).read_bytes() == manifest and not (out / "episodes.parquet").exists()
    assert sorted(p.name for p in (out / "shards").glob("batch-*")) == ["batch-000000.pcb"]


def test_a_corrupted_table_is_not_rebuilt_from_batches_of_other_code(tmp_path, monkeypatch):
    config, out, _ = _complete(tmp_path, monkeypatch)
    (out / "probes.parquet").write_bytes(b"corrupt")
    _other_code(monkeypatch)
    with pytest.raises(RunDirError, match="written by other code"):
        run_study(config, out)
    assert (out / "probes.parquet").read_bytes() == b"corrupt"


def test_a_corrupted_table_is_rebuilt_from_batches_of_this_code(tmp_path, monkeypatch):
    config, out, first = _complete(tmp_path, monkeypatch)
    digests = first.manifest["sha256"]
    (out / "probes.parquet").write_bytes(b"corrupt")
    again = run_study(config, out)
    assert again.manifest["sha256"] == digests and again.manifest["resumed_units"] == 2


def test_every_unit_recomputed_by_new_code_gives_a_run_of_that_code_only(tmp_path, monkeypatch):
    """With every batch gone, the new code recomputes everything: the run holds one identity."""
    from probecommit.store import batches

    config, out, _ = _complete(tmp_path, monkeypatch)
    for path in (out / "shards").glob("batch-*.pcb"):
        path.unlink()
    (out / "episodes.parquet").unlink()
    _other_code(monkeypatch)
    result = run_study(config, out)
    assert result.manifest["code_sha256"] == "f" * 64 and result.manifest["resumed_units"] == 0
    assert {batches.read_header(p)["code"] for p in (out / "shards").glob("batch-*.pcb")} == {"f" * 64}
    assert (out / "shards" / CODE).read_text() == "f" * 64


def test_shards_of_the_earlier_per_unit_layout_are_refused(tmp_path, monkeypatch):
    config, out, _ = _complete(tmp_path, monkeypatch)
    (out / "episodes.parquet").unlink()
    (out / "shards" / "unit-00000.episodes.parquet").write_bytes(b"PAR1")
    with pytest.raises(RunDirError, match="unrecorded"):
        run_study(config, out)


def test_the_manifest_provenance_is_looked_up_while_the_run_computes(tmp_path, monkeypatch):
    """git commit, uncommitted changes and versions come from a thread started with the run (the
    values are the same as looked up at the end), and the thread has ended when the run returns."""
    import threading

    from probecommit.store import rundir

    started = []
    monkeypatch.setattr(rundir, "provenance", lambda: (started.append(threading.current_thread().name)
                                                       or ("abc123", False, {"python": "3"})))
    result = run_study(small_config(instances={"count": 2}, belief={"particles": 16}), tmp_path / "run")
    assert started == ["probecommit-provenance"]
    assert (result.manifest["git_commit"], result.manifest["git_dirty"]) == ("abc123", False)
    assert result.manifest["engine_versions"] == {"python": "3"}
    assert not any(t.name == "probecommit-provenance" for t in threading.enumerate())
