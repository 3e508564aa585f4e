"""``benchmarks/run_parts.py`` times the run's pieces by wrapping package functions by name: each name
must still exist (a rename, ``RunDir.final_episodes`` -> ``final_episodes_table``, broke it unseen)."""

import importlib.util
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_run_parts_wraps_functions_that_exist(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    spec = importlib.util.spec_from_file_location("run_parts_under_test", BENCHMARKS / "run_parts.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    missing = [f"{getattr(owner, '__name__', owner)}.{name}" for owner, name, _ in module.PIECES + module.COMMAND_PIECES
               if not callable(getattr(owner, name, None))]
    assert not missing, f"benchmarks/run_parts.py wraps names the package no longer has: {missing}"
