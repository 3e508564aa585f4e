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
