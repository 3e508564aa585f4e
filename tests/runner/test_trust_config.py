"""Trust configs and runs, by class (issue 38 items 7, 11, 13, 14, 15).

Family ranges hold for fixed truths and contexts exactly as for a sampled box; the leak
check reads truth and context values, not ids; YAML is read under a size and
expanded-node budget (merge keys counted); the memory guard counts the container's limit,
the units held at once and the run's output; a Ray address must answer as Ray.
"""

from __future__ import annotations

import socket
import threading
import time

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probecommit.runner.config import ConfigError, load_config, parse_config
from tests.conftest import small_config

PUSH1D = {"name": "p", "task": "push1d", "repeats": 1, "instances": {"split": "p", "count": 2},
          "probes": {"budget": 2}, "belief": {"particles": 32}, "simulator": {"engine": "analytic"},
          "blind_prior_samples": 200}


def with_instances(base: dict, **instances) -> dict:
    return {**base, "instances": {**base.get("instances", {}), **instances}}


# ----------------------------------------------------------------------------- item 11: fixed truths and contexts


@pytest.mark.parametrize("data, field", [
    (with_instances({"task": "insertion"}, truths=[[1000.0, 0.0]]), "instances.truths"),
    (with_instances(PUSH1D, truths=[[0.3, -1.0, 0.1]], contexts=[[1.0]]), "instances.truths"),
    (with_instances(PUSH1D, truths=[[0.3, 0.0, 0.1]], contexts=[[1.0]]), "instances.truths"),
    (with_instances(PUSH1D, contexts=[[-1.0]]), "instances.contexts"),
    (with_instances({**PUSH1D, "task": "hinge"}, contexts=[[1e9]]), "instances.contexts"),
])
def test_fixed_truths_and_contexts_meet_the_family_ranges(data, field):
    data = {"name": "x", **data}
    data.setdefault("instances", {})
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        parse_config(data)


@given(rows=st.lists(st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-2, 2)), min_size=1, max_size=4))
@settings(max_examples=40, deadline=None)
def test_a_fixed_truth_set_is_accepted_exactly_when_its_box_would_be(rows):
    """Rule parity: fixed truths pass the family's limits iff the box they span (sampled from) does."""
    lows = [min(c) for c in zip(*rows)]
    highs = [max(c) + 1e-3 for c in zip(*rows)]

    def accepted(instances):
        try:
            parse_config(with_instances(PUSH1D, contexts=[[1.0]], **instances))
            return True
        except ConfigError:
            return False

    assert accepted({"truths": [list(r) for r in rows]}) == accepted({"truth_low": lows, "truth_high": highs})


def test_truths_times_contexts_is_bounded():
    truths = [[0.3, 1.0, 0.1]] * 1000
    contexts = [[0.5 + i * 1e-3] for i in range(200)]
    with pytest.raises(ConfigError, match="200,000 instances, more than the 100,000"):
        parse_config(with_instances(PUSH1D, truths=truths, contexts=contexts))


# ----------------------------------------------------------------------------- item 7: the leak check by content


@pytest.fixture(scope="module")
def cal_run(tmp_path_factory):
    from probecommit.runner.study import run_study

    cfg = small_config(name="cal", instances={"split": "cal", "count": 8, "seed": 5}, repeats=1,
                       probes={"budget": 2})
    return run_study(cfg, tmp_path_factory.mktemp("cal") / "run").run_dir


@pytest.mark.parametrize("shared", [8, 7])
def test_the_same_truths_under_other_ids_are_refused(tmp_path, cal_run, shared):
    from probecommit.runner.calibration import calibrate, gates
    from probecommit.runner.study import run_study

    truths = pd.read_parquet(cal_run / "instances.parquet")[["true_x_hole", "true_c"]].to_numpy().tolist()
    truths = truths[:shared] + [[0.123, 0.456]] * (8 - shared)
    cfg = small_config(name="other", instances={"split": "other", "truths": truths}, repeats=1, probes={"budget": 2})
    test = run_study(cfg, tmp_path / "test").run_dir
    for command in (calibrate, gates):
        with pytest.raises(ValueError, match=f"share {shared} instance\\(s\\) by their truth and context values"):
            command(cal_run, test, resamples=100)


# ----------------------------------------------------------------------------- item 13: bounded YAML

MERGE_BOMB = "\n".join(["a0: &a0 {k0: 0, k1: 1}"] + [
    f"a{i}: &a{i} {{<<: [*a{i - 1}], m{i}: [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}]}}" for i in range(1, 12)]) + "\n"
#: Under the old 64-alias cap: eight levels of eight aliases (8**8 numbers) fed to two config fields.
ALIAS_BOMB = "anchors:\n  a: &a [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]\n" + "".join(
    f"  {c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n" for p, c in zip("abcdefg", "bcdefgh")) + \
    "probes: {schedule: *h}\ninstances: {truths: *h}\n"


@pytest.mark.parametrize("text", [MERGE_BOMB, ALIAS_BOMB, "[" * 5000 + "]" * 5000, "a:\n" + "".join(
    "  " * i + f"k{i}:\n" for i in range(1, 400)), "a: &a [1, *a]\n"], ids=["merge", "alias", "flow", "block", "cycle"])
def test_yaml_bombs_are_refused_in_well_under_a_second(text, tmp_path):
    # CPU time, what a bomb costs (the wall clock also counts the tests of another xdist worker)
    start = time.process_time()
    (tmp_path / "c.yaml").write_text(text)
    with pytest.raises(ConfigError, match="c.yaml: .*(nodes|nests|recursive)"):
        load_config(tmp_path / "c.yaml")
    from probecommit.store.yamlsafe import YamlError, load_yaml

    with pytest.raises(YamlError, match="nodes|nests|recursive"):
        load_yaml(text, "bomb.yaml")
    assert time.process_time() - start < 2.0


def test_a_bomb_in_an_existing_runs_config_yaml_is_refused_quickly(tmp_path):
    from probecommit.store.rundir import RunDir, RunDirError

    run = RunDir(tmp_path / "run")
    run.path.mkdir()
    (run.path / "config.yaml").write_text(MERGE_BOMB)
    # CPU time, what a bomb costs (the wall clock also counts the tests of another xdist worker)
    start = time.process_time()
    try:
        run.check_writable("name: x\n")
    except (RunDirError, ValueError) as exc:
        assert "Traceback" not in str(exc)
    assert time.process_time() - start < 2.0


@st.composite
def yaml_graphs(draw):
    """Random anchored YAML with aliases and merge keys at random fan-out."""
    n = draw(st.integers(1, 10))
    lines = ["n0: &n0 {v: 1}"]
    for i in range(1, n):
        refs = draw(st.lists(st.integers(0, i - 1), min_size=1, max_size=6))
        merge = draw(st.booleans())
        items = ", ".join(f"*n{r}" for r in refs)
        body = f"{{<<: [*n{refs[0]}], l{i}: [{items}]}}" if merge else f"[{items}]"
        lines.append(f"n{i}: &n{i} {body}")
    return "\n".join(lines) + "\n"


@given(text=yaml_graphs())
@settings(max_examples=40, deadline=None)
def test_any_alias_and_merge_graph_is_read_or_refused_within_budget(text):
    from probecommit.store.yamlsafe import YamlError, load_yaml

    # CPU time, what a bomb costs (the wall clock also counts the tests of another xdist worker)
    start = time.process_time()
    try:
        load_yaml(text, "g.yaml")
    except YamlError as exc:
        assert "g.yaml" in str(exc)
    assert time.process_time() - start < 3.0


def test_unsafe_tags_are_refused_in_one_line():
    from probecommit.store.yamlsafe import YamlError, load_yaml

    with pytest.raises(YamlError, match="could not determine a constructor"):
        load_yaml("!!python/object/apply:os.system ['true']", "--set model.sigma")


# ----------------------------------------------------------------------------- item 14: the memory guard


def test_the_cgroup_limit_is_read(tmp_path):
    from probecommit.process import memory

    (tmp_path / "grp").mkdir()
    (tmp_path / "grp" / "memory.max").write_text("1073741824\n")
    (tmp_path / "grp" / "memory.current").write_text("268435456\n")
    (tmp_path / "cgroup").write_text("0::/grp\n")
    assert memory.cgroup_headroom(str(tmp_path), str(tmp_path / "cgroup")) == 768 * 1024**2
    (tmp_path / "grp" / "memory.max").write_text("max\n")
    assert memory.cgroup_headroom(str(tmp_path), str(tmp_path / "cgroup")) is None
    v1 = tmp_path / "v1"
    (v1 / "memory" / "g").mkdir(parents=True)
    (v1 / "memory" / "g" / "memory.limit_in_bytes").write_text("2147483648\n")
    (v1 / "memory" / "g" / "memory.usage_in_bytes").write_text("0\n")
    (tmp_path / "cgroup1").write_text("4:memory:/g\n")
    assert memory.cgroup_headroom(str(v1), str(tmp_path / "cgroup1")) == 2 * 1024**3


def test_the_guard_counts_the_units_held_at_once_and_the_output(monkeypatch):
    from probecommit.process import memory
    from probecommit.runner.study import output_rows, preflight, run_concurrency

    cfg = small_config(belief={"particles": 4096})
    one = 4 * 2 * 4096 * 8.0 * ((2 + 2) * 7)  # episodes x particles x bytes of one unit's beliefs
    monkeypatch.setattr(memory, "available_bytes", lambda: int(2 * one * 1.5))
    preflight(cfg, 1)
    with pytest.raises(MemoryError, match="4 work unit\\(s\\) at once"):
        preflight(cfg, 4)
    assert run_concurrency(cfg, workers=3) == 3 and run_concurrency(cfg, threads=2) == 4
    assert output_rows(cfg) == 6 * 2 * (5 + 1) * 3
    monkeypatch.undo()
    big = small_config(instances={"count": 100_000}, repeats=1000, unit_instances=1, belief={"particles": 8})
    with pytest.raises(MemoryError, match="episode rows, more than"):
        preflight(big, 1)


# ----------------------------------------------------------------------------- item 15: a port that is not Ray


def test_a_port_that_accepts_but_is_not_ray_fails_within_seconds():
    from probecommit.runner.study import check_reachable

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    port = server.getsockname()[1]
    start = time.perf_counter()
    with pytest.raises(RuntimeError, match="did not answer as a Ray"):
        check_reachable(f"127.0.0.1:{port}", timeout_s=1.0)
    assert time.perf_counter() - start < 3.0
    server.close()
