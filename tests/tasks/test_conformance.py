"""Conformance: every registered family passes :func:`probecommit.check_family` (the shipped checker,
built from the conformance suite that lived here), and the checker itself can fail: a family with
mismatched names, mismatched latents or a negative truth for a positive latent is caught, each
failure naming the declaration to fix."""

from __future__ import annotations

import dataclasses
from typing import Literal

import pytest

import probecommit
from probecommit.runner.family_check import check_family, installed, small_config
from probecommit.tasks.registry import families

FAMILIES = sorted(families())
PAIRS = [(name, engine) for name in FAMILIES for engine in families()[name].engines]


@pytest.mark.parametrize("family", FAMILIES)
def test_every_family_passes_its_model_checks(family):
    report = check_family(family, engines=[], study=False)
    assert report.ok and "grown set in blocks" in report.passed


@pytest.mark.parametrize("family,engine", PAIRS)
def test_every_engine_passes_its_simulator_and_study_checks(family, engine):
    if not installed(engine):
        pytest.skip(f"{engine} not installed")
    report = check_family(family, engines=[engine])
    assert report.ok and f"study {engine}" in report.passed


def test_check_family_is_shipped_at_the_package_root():
    assert probecommit.check_family is check_family
    assert small_config(families()["push1d"], "analytic").task.family == "push1d"


def _variant(spec, **changes):
    """An unregistered copy of a family's spec written by hand, with its config class changed (a planted mistake)."""
    attrs = {"__annotations__": {"family": Literal["push1d"]}, "family": "push1d", **changes}
    config = type("Planted", (spec.config,), attrs)
    return dataclasses.replace(spec, config=config, declaration=None)


def test_mismatched_names_are_caught_naming_the_declaration():
    spec = dataclasses.replace(families()["push1d"], name="push_one", declaration=None)  # written by hand
    report = check_family(spec, study=False, raise_errors=False)
    assert [f[:2] for f in report.failures] == [("names", "the config class's `family` default")]


def test_mismatched_latents_are_caught_naming_the_declaration():
    report = check_family(_variant(families()["push1d"], latent_names=("mu", "mass", "k_d")), study=False, raise_errors=False)
    assert report.failures[0][:2] == ("latents", "the model's `latent_names` or the config's `latent_names`")


def test_a_negative_truth_for_positive_latents_is_caught(monkeypatch):
    from probecommit.tasks.config import TaskConfigBase

    planted = _variant(families()["push1d"], check_truth_box=lambda self, lo, hi, field: None)
    report = check_family(planted, study=False, raise_errors=False)
    assert report.failures[0][:2] == ("positivity", "the config's `check_truth_box`")
    # And a family that forgets to declare positivity is not checked for it, by design (nothing declared).
    assert TaskConfigBase.positive_latents is False


def test_a_failure_raises_one_line_per_check():
    spec = dataclasses.replace(families()["push1d"], name="push_one", declaration=None)  # written by hand
    with pytest.raises(probecommit.FamilyCheckError, match=r"names: fix the config class's `family` default"):
        check_family(spec, study=False)


def test_a_declared_family_is_told_to_fix_its_declaration():
    import numpy as np

    from probecommit.tasks.adapters.functions import function_family
    from probecommit.tasks.declare import Latent
    from probecommit.tasks.registry import unregister

    spec = function_family("bad_name", latents=[Latent("k", "", 1.0, 2.0)], predict=lambda th, u: th[..., 0] * u[..., 0],
                           loss=lambda th, a, c: np.abs(th[..., 0] - a[..., 0]), probe_grid=[1.0], action_grid=[1.0, 2.0],
                           sigma=0.1)
    try:
        assert check_family("bad_name", study=False).ok
        report = check_family(dataclasses.replace(spec, name="bad_name_2"), study=False, raise_errors=False)
    finally:
        unregister("bad_name")
    assert report.failures[0][:2] == ("names", "the Declaration's `name` (and the model's base class: DeclaredModel)")
