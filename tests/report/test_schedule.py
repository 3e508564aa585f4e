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
    steps = []
    done = side_by_side(order, needs, 2, lambda pool, name: pool.submit(_fake_target, name, str(tmp_path), False),
                        lambda step, *args: steps.append(step))
    assert done == {name: (f"/results/{name}", 0.3) for name in order}
    spans = {name: json.loads((tmp_path / name).read_text()) for name in order}
    assert spans["c"][0] >= spans["a"][1] and spans["d"][0] >= max(spans["c"][1], spans["b"][1])
    assert "targets side by side (running: a, b)" in steps  # a and b ran side by side (launched together)


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


def _late_reader(name: str, log: str, markers: str) -> tuple[str, float]:
    """A target that starts, then waits for its late need ``slow`` (``wait_for``) before reading it."""
    from probecommit.report.schedule import wait_for

    start = time.time()
    wait_for(markers, ["slow"], poll_s=0.05)
    Path(log, name).write_text(json.dumps([start, time.time()]))
    return f"/results/{name}", 0.3


def test_a_late_need_lets_a_target_start_before_it_and_wait_where_it_reads_it(tmp_path):
    markers = tmp_path / "markers"

    def launch(pool, name):
        if name == "reader":
            return pool.submit(_late_reader, name, str(tmp_path), str(markers))
        return pool.submit(_fake_target, name, str(tmp_path), False)

    steps = []
    done = side_by_side(["slow", "reader"], {"reader": ("slow",)}, 2, launch, lambda step, *args: steps.append(step),
                        markers=markers, late={"reader": ("slow",)})
    assert set(done) == {"slow", "reader"}
    assert "targets side by side (running: reader, slow)" in steps  # started beside it
    slow, reader = (json.loads((tmp_path / n).read_text()) for n in ("slow", "reader"))
    assert slow[1] <= reader[1]  # and read it only once it was done
    assert not markers.exists()  # gone once every target has finished


def test_a_target_waiting_for_a_late_need_that_failed_stops(tmp_path):
    markers = tmp_path / "markers"

    def launch(pool, name):
        if name == "reader":
            return pool.submit(_late_reader, name, str(tmp_path), str(markers))
        return pool.submit(_fake_target, name, str(tmp_path), True)

    with pytest.raises(RuntimeError, match="slow failed"):
        side_by_side(["slow", "reader"], {"reader": ("slow",)}, 2, launch, lambda *args: None, markers=markers,
                     late={"reader": ("slow",)})
    assert not (tmp_path / "reader").exists()


def test_ready_targets_start_longest_chain_first(monkeypatch):
    """explain's start need (insertion) starts first: the chain through explain is the longest."""
    from probecommit.report import schedule

    order = paper.resolve(["all"])
    needs = {t: tuple(n for n in paper.TARGETS[t].needs if n not in schedule.LATE_NEEDS.get(t, ())) for t in order}
    real = schedule.chain_seconds(order, needs)
    assert max(real, key=real.get) == "insertion"  # explain starts after it alone
    monkeypatch.setattr(schedule, "EXPECTED_S", {"a": 10.0, "b": 1.0, "c": 5.0, "d": 3.0})
    chains = schedule.chain_seconds(["a", "b", "c", "d"], {"c": ("b",), "d": ("a", "b")})
    assert chains == {"a": 13.0, "b": 6.0, "c": 5.0, "d": 3.0}
    # A small target read late by a long one starts before a larger one nothing waits for.
    monkeypatch.setattr(schedule, "EXPECTED_S", {"x": 1.0, "y": 5.0, "r": 100.0})
    late = schedule.chain_seconds(["x", "y", "r"], {}, {"r": ("x",)})
    assert late["x"] == 1.0 + schedule.LATE_SHARE * 100.0 > late["y"] == 5.0


def test_a_waiting_target_whose_reproduction_was_killed_stops(tmp_path, monkeypatch):
    """An orphan (its main process killed, so nothing will mark its late need done) raises, not polls for ever."""
    from probecommit.report import schedule

    pids = iter([100, 100, 1])  # the parent at the start, still there, then gone (re-parented to init)
    monkeypatch.setattr(schedule.os, "getppid", lambda: next(pids))
    with pytest.raises(RuntimeError, match="reproduction ended before engines was done"):
        schedule.wait_for(str(tmp_path), ["engines"], poll_s=0.0)
