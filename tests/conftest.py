"""Shared fixtures: small analytic studies (no engine needed)."""

import pytest

from probecommit.runner.config import parse_config


def small_config(**overrides) -> "StudyConfig":  # noqa: F821
    data = {
        "name": "small",
        "seed": 11,
        "repeats": 2,
        "instances": {"split": "test", "count": 6, "seed": 3},
        "probes": {"schedule": "random", "budget": 5},
        "belief": {"particles": 256},
        "simulator": {"engine": "analytic", "boundary_offset": 0.905},
        "unit_instances": 2,
        "blind_prior_samples": 2000,
    }
    for key, value in overrides.items():
        data[key] = {**data[key], **value} if isinstance(value, dict) and key in data else value
    return parse_config(data)


def table_iii_like_run(root):
    """A small analytic random run named as Table III's test run (5 instances, eight taps), loaded: what the explain
    steps that re-commit Table III's own run (ex34, ex43) are tested on."""
    from probecommit.runner.replay import load_run
    from probecommit.runner.study import run_study

    cfg = small_config(name="B_test_random", instances={"split": "test", "count": 5, "seed": 3},
                       probes={"schedule": "random", "budget": 8})
    return load_run(run_study(cfg, root / "run").run_dir)


def cal_test_runs(root, seeds: tuple[int, int], count: int, repeats: int, **overrides) -> dict:
    """A calibration and a test run of the small config ("cal" and "test" splits, one instance seed each): the
    pair that calibration, gate, chunking, margin-search and report tests read. Returns their run directories."""
    from probecommit.runner.study import run_study

    out = {}
    for split, seed in zip(("cal", "test"), seeds):
        cfg = small_config(name=split, instances={"split": split, "count": count, "seed": seed}, repeats=repeats,
                           **overrides)
        out[split] = run_study(cfg, root / split).run_dir
    return out


@pytest.fixture
def make_config():
    return small_config


def _shared_fixture_group(items) -> str | None:
    """The xdist group of one test module's items: the first session-scoped fixture of the test tree they use,
    else the module itself when they use a module-scoped one; None when they share nothing built once."""
    session, module = set(), False
    for item in items:
        info = getattr(item, "_fixtureinfo", None)
        for defs in (info.name2fixturedefs.values() if info else ()):
            fixture = defs[-1]
            if not fixture.baseid.startswith("tests"):
                continue  # pytest's own (tmp_path_factory is session-scoped, and cheap)
            if fixture.scope == "session":
                session.add(fixture.argname)
            module = module or fixture.scope == "module"
    if session:
        return min(session)
    return items[0].nodeid.split("::")[0] if module else None


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under ``pytest -n 2 --dist loadgroup`` (make test) every ungrouped test is its own unit of work, so the
    tests of one module alternate between the two workers and each would build the module's (or the session's)
    expensive fixture again. A module whose tests share such a fixture goes to one worker as one group (by the
    session fixture's name, so every module reading the scratch publication shares one build), before xdist
    reads the groups. Without xdist the mark does nothing."""
    modules: dict[str, list] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::")[0], []).append(item)
    for module_items in modules.values():
        group = _shared_fixture_group(module_items)
        for item in module_items if group else ():
            if not item.get_closest_marker("xdist_group"):  # a test that names its own group keeps it
                item.add_marker(pytest.mark.xdist_group(group))
