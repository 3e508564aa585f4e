"""A run validates its config once and builds its model once, and hands both down to every unit.

Counted over a whole ``probecommit run`` (CLI, with overrides, several units computed one by one):
before, the config was validated for the file, again for the overrides and again in the units,
and the model built in two preflights and once per unit. Worker processes (``--workers``) and Ray
tasks receive the config as data and build it again, once per worker process, not once per unit.
"""

import collections
import json
import pickle

import pytest
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.runner import config as config_module
from probecommit.runner import study
from probecommit.tasks import registry


@pytest.fixture
def counts(monkeypatch):
    """Calls of the model builder and of the config's validation."""
    seen = collections.Counter()
    build_model, validate = registry.build_model, config_module.StudyConfig.model_validate.__func__

    def counted_build(task_config):
        seen["model builds"] += 1
        return build_model(task_config)

    def counted_validate(cls, *args, **kwargs):
        seen["validations"] += 1
        return validate(cls, *args, **kwargs)

    monkeypatch.setattr(registry, "build_model", counted_build)
    monkeypatch.setattr(config_module.StudyConfig, "model_validate", classmethod(counted_validate))
    return seen


@pytest.mark.parametrize("group_episodes", [1, 256])  # every unit alone, and the units in one group
def test_a_multi_unit_run_validates_once_and_builds_once(tmp_path, monkeypatch, counts, group_episodes):
    from importlib import resources

    monkeypatch.setattr(study, "GROUP_EPISODES", group_episodes)
    demo = str(resources.files("probecommit") / "configs" / "demo.yaml")
    result = CliRunner().invoke(app, ["run", demo, "simulator.engine=analytic", "instances.count=6", "repeats=1",
                                      "belief.particles=32", "unit_instances=2", "blind_prior_samples=200",
                                      "--threads", "1", "-o", str(tmp_path / "run")])
    assert result.exit_code == 0, result.output
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["units"] == 3
    assert counts == {"model builds": 1, "validations": 1}


def test_a_worker_process_builds_the_parts_once_for_all_its_units(make_config, counts):
    """What a worker process (or a Ray worker) does with each group of units it is sent: the
    parts arrive pickled as config data and are rebuilt once for that process."""
    parts = study.RunParts.build(make_config(unit_instances=1))
    assert counts == {"model builds": 1, "validations": 1}
    study._parts_of_data.cache_clear()  # a fresh worker process
    received = [pickle.loads(pickle.dumps(parts)) for _ in range(3)]  # three groups sent to one worker
    assert received[0] is received[1] is received[2] and received[0] is not parts
    assert counts == {"model builds": 2, "validations": 2}  # once in the driver, once in the worker
    assert received[0].config == parts.config


def test_overrides_on_the_files_mapping_keep_each_errors_blame(tmp_path, counts):
    """Overrides go into the file's mapping before its one validation; the nested ``task`` form is
    validated then overridden; a bad file is named alone, a bad override with the overrides."""
    from probecommit.runner.config import ConfigError
    from probecommit.runner.overrides import load_with_overrides, parse_override

    flat = tmp_path / "flat.yaml"
    flat.write_text("name: f\ntask: insertion\nsimulator: {engine: analytic}\ninstances: {count: 2}\n")
    assert load_with_overrides(flat, [parse_override("model.sigma=0.4")]).model.sigma == 0.4
    assert counts["validations"] == 1
    nested = tmp_path / "nested.yaml"
    nested.write_text("name: n\ntask: {family: insertion, model: {sigma: 0.5}, simulator: {engine: analytic}}\n")
    assert load_with_overrides(nested, [parse_override("model.sigma=0.4")]).model.sigma == 0.4
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: b\nrepeats: 0\n")
    with pytest.raises(ConfigError, match=r"^.*bad\.yaml: invalid config field 'repeats'"):
        load_with_overrides(bad, [parse_override("model.sigma=0.4")])
    with pytest.raises(ConfigError, match=r"flat\.yaml with model\.sigma=-1: invalid config field 'model\.sigma'"):
        load_with_overrides(flat, [parse_override("model.sigma=-1")])
