"""Config validation: one-line errors naming the field."""

import pytest

from probecommit.runner.config import ConfigError, load_config, parse_config


@pytest.mark.parametrize(
    "data,field",
    [
        ({"belief": {"particles": 0}}, "belief.particles"),
        ({"model": {"sigma": -0.5}}, "model.sigma"),
        ({"model": {"sigma": 0}}, "model.sigma"),
        ({"simulator": {"engine": "gazebo"}}, "simulator.engine"),
        ({"probes": {"budget": 3, "budgets": [1, 5]}}, "probes"),
        ({"repeats": 0}, "repeats"),
        ({"belief": {"nu": 1.5}}, "belief.nu"),
        ({"unknown_field": 1}, "unknown_field"),
    ],
)
def test_bad_values_name_the_field(data, field):
    with pytest.raises(ConfigError) as err:
        parse_config(data)
    message = str(err.value)
    assert f"'{field}" in message
    assert "\n" not in message


def test_unknown_engine_lists_choices():
    with pytest.raises(ConfigError, match="mujoco"):
        parse_config({"simulator": {"engine": "gazebo"}})


def test_yaml_errors(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_config(bad)
    listy = tmp_path / "list.yaml"
    listy.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="mapping"):
        load_config(listy)
