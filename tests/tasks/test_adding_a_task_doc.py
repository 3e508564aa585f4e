"""docs/adding-a-task.md builds what it says: its worked example family, written from the page's own
code blocks into a temporary folder, passes check_family, runs a tiny study, is audited and drives a
Session; and (slow) added as a folder under tasks/ only, every CLI command the page lists works on it."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "adding-a-task.md"


def blocks() -> list[tuple[str, str]]:
    """``(language, code)`` of every fenced block of the page, in order."""
    return re.findall(r"```(\w+)\n(.*?)```", DOC.read_text(), flags=re.S)


def write_files(folder: Path) -> dict[str, Path]:
    """Write every block whose first line is ``# file: PATH`` under ``folder``."""
    written = {}
    for _, code in blocks():
        first, _, rest = code.partition("\n")
        if first.startswith("# file: "):
            path = folder / first.removeprefix("# file: ").strip()
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(code)
            written[path.name] = path
    return written


def block(tag: str) -> str:
    """The python block whose first line is ``# <tag>``."""
    found = [code for lang, code in blocks() if lang == "python" and code.startswith(f"# {tag}\n")]
    assert len(found) == 1, f"docs/adding-a-task.md has {len(found)} '# {tag}' blocks"
    return found[0]


def test_the_docs_example_family_checks_runs_audits_and_drives_a_session(tmp_path, monkeypatch):
    from probecommit.audit.pipeline import audit
    from probecommit.runner.config import load_config
    from probecommit.runner.family_check import check_family
    from probecommit.runner.study import run_study
    from probecommit.tasks.registry import families

    files = write_files(tmp_path)
    assert {"__init__.py", "sim_closed_form.py", "glide-cal.yaml", "glide-test.yaml"} <= set(files)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.chdir(tmp_path)
    import importlib

    from probecommit.tasks.registry import unregister

    importlib.import_module("glide")
    try:
        assert families()["glide"].declaration.latent_names == ("mu", "m")
        assert families()["glide"].engines == ("analytic", "closed_form")
        exec(compile(block("check"), "adding-a-task.md#check", "exec"), {})
        assert "study closed_form" in check_family("glide").passed
        result = run_study(load_config("glide-test.yaml"), tmp_path / "runs" / "glide-test")
        table = audit(result.run_dir, resamples=100).table
        assert set(table["k"]) == {0, 1, 3} and table["coverage"].between(0, 1).all()
        exec(compile(block("session"), "adding-a-task.md#session", "exec"), {})
    finally:
        unregister("glide")
        sys.modules.pop("glide", None)


@pytest.mark.slow
def test_added_as_a_folder_only_every_cli_command_of_the_page_works(tmp_path):
    extra = tmp_path / "tasks_extra"
    files = write_files(extra)
    for name in ("glide-cal.yaml", "glide-test.yaml"):
        files[name].rename(tmp_path / name)
    # The folder is found by the registry's package scan of probecommit.tasks (its __path__ extended
    # to the temporary folder, as if the folder sat in src/probecommit/tasks/): no other file edited.
    launcher = ("import sys, probecommit.tasks as t; t.__path__.append(sys.argv.pop(1)); "
                "from probecommit.cli.app import main; sys.argv[0] = 'probecommit'; main()")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    commands = [line.split("#")[0].strip() for lang, code in blocks() if lang == "bash" for line in code.splitlines()]
    commands = [c for c in commands if c.startswith("probecommit ")]
    assert len(commands) == 7
    for command in ["probecommit tasks --check glide", *commands]:
        args = shlex.split(command)[1:]
        done = subprocess.run([sys.executable, "-c", launcher, str(extra), *args], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, f"{command}:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
        if args == ["tasks"]:
            assert "glide" in done.stdout
    assert (tmp_path / "runs" / "glide-test" / "episodes.parquet").is_file()
