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
from probecommit.tasks.planar_slide import SPEC as SLIDE

class ToySlideConfig(SLIDE.config):
    family: Literal["toy_slide"] = "toy_slide"

SPEC = TaskSpec(name="toy_slide", config=ToySlideConfig, build_model=SLIDE.build_model,
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


def test_every_folder_under_tasks_is_discovered_without_a_list():
    from pathlib import Path

    import probecommit.tasks as package
    from probecommit.tasks.registry import builtin_packages

    folders = {p.name for p in Path(package.__path__[0]).iterdir() if (p / "__init__.py").is_file()}
    assert builtin_packages() == sorted(folders)
    assert folders - {"adapters"} <= set(families())  # every folder but the adapters' registers a family


def test_the_default_family_is_the_one_spec_that_says_so(monkeypatch):
    import dataclasses

    from probecommit.runner.config import parse_config
    from probecommit.tasks import registry

    assert registry.default_family() == "insertion" and parse_config({}).task.family == "insertion"
    monkeypatch.setitem(registry._REGISTRY, "push1d", dataclasses.replace(families()["push1d"], default=True))
    with pytest.raises(UnknownTaskError, match="must name its task family .* default families registered: insertion, push1d"):
        registry.default_family()


def test_register_after_the_config_module_is_imported_makes_configs_naming_it_valid():
    """A user's script imports probecommit (the config union is built) and registers afterwards."""
    script = textwrap.dedent('''
        import numpy as np
        from probecommit.runner.config import parse_config   # builds the task union now
        from probecommit.tasks.adapters.functions import function_family
        from probecommit.tasks.declare import Latent
        function_family("late_family", latents=[Latent("k", "", 1.0, 2.0, positive=True)],
                        predict=lambda th, u: th[..., 0] * u[..., 0],
                        loss=lambda th, a, c: np.abs(th[..., 0] - a[..., 0]),
                        probe_grid=[1.0, 2.0], action_grid=np.linspace(1, 2, 11), sigma=0.1)
        config = parse_config({"task": "late_family", "model": {"sigma": 0.2}})
        print(type(config.task).__name__, config.task.model.sigma)
    ''')
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["late_family_config", "0.2"]
