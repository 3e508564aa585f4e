"""The registry: lookups with one-line errors, and third-party families through entry points."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from probecommit.tasks.registry import UnknownTaskError, families, get, simulator_class


def test_unknown_family_and_missing_engine_list_what_exists():
    with pytest.raises(UnknownTaskError, match=r"unknown task family 'juggling'; registered: .*insertion"):
        get("juggling")
    with pytest.raises(UnknownTaskError, match=r"has no 'gazebo' simulator; it has: analytic, mujoco, pybullet, sapien"):
        simulator_class("insertion", "gazebo")


def test_builtin_families_register_with_their_engines():
    specs = families()
    assert {"insertion", "planar_slide"} <= set(specs)
    assert {"analytic", "mujoco"} <= set(specs["insertion"].engines)
    assert simulator_class("insertion", "analytic").engine == "analytic"


THIRD_PARTY = '''
from typing import Literal
from probecommit.tasks.base import TaskSpec
from probecommit.tasks.planar_slide import build_model
from probecommit.tasks.planar_slide.config import PlanarSlideConfig

class ToySlideConfig(PlanarSlideConfig):
    family: Literal["toy_slide"] = "toy_slide"

SPEC = TaskSpec(name="toy_slide", config=ToySlideConfig, build_model=build_model,
                simulators={"analytic": "probecommit.tasks.planar_slide.sim_analytic:AnalyticPlanarSlideSimulator"},
                example={"instances": {"contexts": [[1.0, 0.0]]}})
'''

CHECK = '''
from probecommit.runner.config import parse_config
from probecommit.runner.study import run_study
cfg = parse_config({"name": "toy", "task": "toy_slide", "repeats": 1, "instances": {"count": 2, "contexts": [[1.0, 0.0]]},
                    "probes": {"budget": 2}, "belief": {"particles": 32}, "blind_prior_samples": 200})
result = run_study(cfg, OUT)
print("family", cfg.family, "rows", len(result.episodes))
'''


def test_a_third_party_family_registers_through_the_entry_point_group(tmp_path):
    pkg = tmp_path / "toyslide"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(THIRD_PARTY)
    dist = tmp_path / "toyslide-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toyslide\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[probecommit.tasks]\ntoy_slide = toyslide:SPEC\n")
    code = CHECK.replace("OUT", repr(str(tmp_path / "run")))
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(tmp_path) + ":" + ":".join(sys.path), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0, out.stderr[-2000:]
    assert "family toy_slide rows" in out.stdout
