"""`probecommit reproduce all --quick` end to end, published and verified."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.report import paper
from probecommit.report.verify import verify


def test_targets_resolve_with_dependencies_and_aliases():
    assert paper.resolve(["beyond"]) == ["insertion", "breadth", "beyond"]
    assert paper.resolve(["table-5", "table-2"]) == ["insertion", "breadth"]
    # The paper's own numbering and labels: Table VI engines, Table VII the (simulated) arm, Fig. 5 too.
    assert paper.resolve(["table-6", "tab:hardware", "fig-5", "tab:setup"]) == ["engines", "robot", "setup"]
    with pytest.raises(ValueError, match="unknown reproduce target 'table-9'"):
        paper.resolve(["table-9"])
    assert paper.resolve(["all"])[0] == "insertion"
    with pytest.raises(ValueError, match="unknown reproduce target 'table-99'"):
        paper.resolve(["table-99"])


def test_markdown_tables_become_latex():
    tex = paper.markdown_to_latex("| a | b_1 |\n|---|---|\n| 1 & 2 | 50% |\n")
    assert r"\toprule" in tex and r"a & b\_1 \\" in tex and r"1 \& 2 & 50\% \\" in tex


@pytest.mark.slow
def test_reproduce_all_quick_then_publish_and_verify(tmp_path):
    repo = tmp_path / "repo"
    result = CliRunner().invoke(app, ["reproduce", "all", "--quick", "-o", str(tmp_path / "runs"), "--publish-to", str(repo)])
    assert result.exit_code == 0, result.output
    folders = {name: tmp_path / "runs" / name / "results" for name in ("insertion", "breadth", "beyond")}
    for folder in folders.values():
        assert (folder / "results.json").is_file()
    assert (folders["breadth"] / "table_II_breadth.tex").is_file() and (folders["breadth"] / "fig_breadth_budget.pdf").is_file()
    assert (folders["insertion"] / "table_V_testc.tex").is_file()
    text = (repo / "REPRODUCTION.md").read_text()
    assert "Table II" in text and "Beyond the paper" in text
    page = (repo / "results" / "paper" / "report.html").read_text()
    assert "data:image/png;base64," in page and "<table>" in page and "http" not in page.split("<body>")[1][:500]
    report = verify(repo)
    assert report.ok, report.failures[:5]
    # Every study of `all` is checked: its tables rendered again, and the recomputed studies' numbers recomputed.
    assert report.counts["recomputed"] > 1000 and report.counts["traced"] >= 35
    assert not [n for n in report.notes if "not rendered again" in n]


def test_setup_target_writes_table_1_and_fig_1b(tmp_path):
    from probecommit.report import paper

    done = paper.reproduce(["table-1"], tmp_path, quick=True)
    results = tmp_path / "setup" / "results"
    assert done["targets"] == {"setup": str(results)}
    table = (results / "table_I_setup.md").read_text()
    for family in paper.SETUP_ORDER:
        assert f"| {family} |" in table
    assert (results / "fig_1b_overview_belief.png").is_file() and (results / "fig_1b_overview_belief.pdf").is_file()
    assert done["machine"]["cores"] >= 1 and done["machine"]["cpu"]


def test_publishing_a_target_again_drops_files_it_no_longer_makes(tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    for folder, name in ((first, "table_9.md"), (second, "table_VII_hardware_simulated_rig.md")):
        folder.mkdir()
        (folder / name).write_text("| a |\n|---|\n| 1 |\n")
        (folder / "results.json").write_text('{"results": {}}')
    paper.publish({"robot": first}, tmp_path / "repo")
    dest = paper.publish({"robot": second}, tmp_path / "repo") / "robot"
    assert sorted(p.name for p in dest.iterdir()) == ["MANIFEST.json", "results.json",
                                                      "table_VII_hardware_simulated_rig.md"]


def test_with_model_switches_the_model_a_replay_builds():
    """The decisive-tap figure replays the development run under the corrected model: the copy
    must reach the task section (a copy of the study config's ``model`` property changed nothing)."""
    from probecommit.studies.insertion import with_model
    from probecommit.runner.config import parse_config
    from probecommit.runner.build import build_model

    cfg = parse_config({"name": "t", "task": "insertion", "instances": {"count": 1}})
    new = with_model(cfg, boundary="corrected", delta=0.905)
    assert (cfg.model.boundary, new.model.boundary) == ("deployed", "corrected")
    assert build_model(new).variant == "corrected" and build_model(cfg).variant == "deployed"


def test_targets_are_registered_once_each_with_their_needs_first():
    """Reproduction targets come from ``register`` calls (no module-level mutation elsewhere): a
    second registration of a name or paper item, or a need not yet registered, is refused."""
    from probecommit.report import paper

    assert list(paper.TARGETS)[:3] == ["insertion", "breadth", "beyond"] and paper.ALIASES["fig-1"] == "figures"
    for target in paper.TARGETS.values():
        assert all(list(paper.TARGETS).index(need) < list(paper.TARGETS).index(target.name) for need in target.needs)
    with pytest.raises(ValueError, match="'insertion' is registered twice"):
        paper.register(paper.Target("insertion", (), (), lambda *a: None))
    with pytest.raises(ValueError, match="'tab:audit' is registered twice"):
        paper.register(paper.Target("other", (), (), lambda *a: None), ("tab:audit",))
    with pytest.raises(ValueError, match="needs 'later'"):
        paper.register(paper.Target("other", (), ("later",), lambda *a: None))
    assert "other" not in paper.TARGETS
