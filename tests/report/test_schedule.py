"""Reproduction targets side by side (issue 42, target 4): order kept, failures raised, numbers unchanged."""

import json
import time
from pathlib import Path

import pytest

from probecommit.report import paper
from probecommit.report.schedule import side_by_side


def _fake_target(name: str, log: str, fail: bool) -> tuple[str, float]:
    """A target that records when it ran (in a spawned process)."""
    start = time.time()
    time.sleep(1.5 if name.startswith("slow") else 0.3)
    Path(log, name).write_text(json.dumps([start, time.time()]))
    if fail:
        raise RuntimeError(f"{name} failed")
    return f"/results/{name}", 0.3


def test_targets_start_once_what_they_read_is_done(tmp_path):
    needs = {"c": ("a",), "d": ("c", "b")}
    order = ["a", "b", "c", "d"]
    done = side_by_side(order, needs, 2, lambda pool, name: pool.submit(_fake_target, name, str(tmp_path), False),
                        lambda *args: None)
    assert done == {name: (f"/results/{name}", 0.3) for name in order}
    spans = {name: json.loads((tmp_path / name).read_text()) for name in order}
    assert spans["c"][0] >= spans["a"][1] and spans["d"][0] >= max(spans["c"][1], spans["b"][1])
    assert spans["b"][0] < spans["a"][1]  # a and b ran side by side


def test_a_failed_target_is_raised_and_what_needs_it_never_starts(tmp_path):
    needs = {"c": ("a",)}
    with pytest.raises(RuntimeError, match="a failed"):
        side_by_side(["a", "b", "c"], needs, 2,
                     lambda pool, name: pool.submit(_fake_target, name, str(tmp_path), name == "a"), lambda *args: None)
    assert (tmp_path / "b").is_file() and not (tmp_path / "c").exists()


def test_lanes_follow_workers_cpus_and_targets(monkeypatch):
    monkeypatch.setattr("os.cpu_count", lambda: 2)
    assert paper.side_by_side_lanes(1, 10) == 1
    assert paper.side_by_side_lanes(4, 10) == 2
    assert paper.side_by_side_lanes(2, 1) == 1


@pytest.mark.slow
def test_side_by_side_gives_the_numbers_of_one_after_the_other(tmp_path):
    targets = ["setup", "robot"]
    one = paper.reproduce(targets, tmp_path / "one", quick=True)
    two = paper.reproduce(targets, tmp_path / "two", quick=True, workers=2)
    assert two.get("side_by_side") == 2 and "side_by_side" not in one
    for name in targets:
        a = json.loads((Path(one["targets"][name]) / "results.json").read_text())
        b = json.loads((Path(two["targets"][name]) / "results.json").read_text())
        assert a == b, name


def test_a_target_that_read_results_not_yet_made_runs_again_after_them(tmp_path):
    """breadth reads insertion's results when they are there: finished first, it is made again after."""
    import shutil

    log = tmp_path / "log"
    log.mkdir()
    runs = []

    def launch(pool, name):
        runs.append(name)
        return pool.submit(_fake_target, name if runs.count(name) == 1 else f"{name}-again", str(log), False)

    done = side_by_side(["slow", "reader"], {}, 2, launch, lambda *args: None, {"reader": ("slow",)})
    assert runs.count("reader") == 2 and runs.count("slow") == 1
    spans = {p.name: json.loads(p.read_text()) for p in log.iterdir()}
    assert spans["reader"][1] < spans["slow"][1] <= spans["reader-again"][0]  # ran beside it, then after it
    assert done["reader"][1] == pytest.approx(0.6)
    shutil.rmtree(log)
