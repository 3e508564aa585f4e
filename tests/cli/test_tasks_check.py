"""``probecommit tasks --check NAME`` runs check_family: every check listed, a failure exits 1 naming
the declaration to fix, an unknown family exits 2 in one line."""

from __future__ import annotations

import dataclasses

from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.tasks import registry


def test_a_family_that_passes_lists_its_checks():
    result = CliRunner().invoke(app, ["tasks", "--check", "planar_slide"])
    assert result.exit_code == 0, result.output
    assert "ok   latents" in result.output and "family planar_slide: all 11 checks passed" in result.output


def test_a_failing_family_exits_1_naming_the_declaration(monkeypatch):
    spec = registry.families()["push1d"]

    class Planted(spec.config):
        latent_names = ("mu", "mass", "k_d")

    # A copy written by hand (no declaration): the failure names the hand-written attribute.
    monkeypatch.setitem(registry._REGISTRY, "push1d", dataclasses.replace(spec, config=Planted, declaration=None))
    result = CliRunner().invoke(app, ["tasks", "--check", "push1d"])
    assert result.exit_code == 1
    assert "FAIL latents: fix the model's `latent_names` or the config's `latent_names`" in result.output


def test_an_unknown_family_is_one_line():
    result = CliRunner().invoke(app, ["tasks", "--check", "juggling"])
    assert result.exit_code == 2 and result.output.startswith("error: unknown task family 'juggling'")


def test_every_engine_hint_names_an_extra_that_exists():
    """`probecommit tasks` tells a user `pip install 'probecommit[EXTRA]'` for a missing engine:
    each EXTRA must be one pyproject declares (the Gymnasium engine's extra is `gym`)."""
    import tomllib
    from pathlib import Path

    from probecommit.runner.family_check import ENGINE_EXTRAS, ENGINE_PACKAGES

    extras = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert set(ENGINE_PACKAGES) == set(ENGINE_EXTRAS)
    assert all(extra in extras for extra in ENGINE_EXTRAS.values())
