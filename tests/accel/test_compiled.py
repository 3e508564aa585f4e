"""How kernels are provided: the ahead-of-time build, its freshness check and its argument checks."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

from probecommit.accel import compiled, executors


def _child(code: str, **env: str) -> subprocess.CompletedProcess:
    full = {k: v for k, v in os.environ.items() if k != "PROBECOMMIT_KERNELS"}
    return subprocess.run([sys.executable, "-c", code], env={**full, **env}, capture_output=True, text=True, timeout=300)


def test_signatures_are_read_without_numba():
    assert compiled._argument_specs("i8[:, ::1](f8[:, ::1], f8[:, :], b1[::1], f8, i8)") == [
        ("float64", 2, True), ("float64", 2, False), ("bool", 1, True), None, None]
    assert compiled._argument_specs("Tuple((b1, f8[::1]))(u8[:, ::1], f8[:, :, ::1])") == [
        ("uint64", 2, True), ("float64", 3, True)]
    assert compiled._argument_specs("void(f8[::1], f8[::1])") == [("float64", 1, True)] * 2
    with pytest.raises(ValueError, match="cannot read argument"):
        compiled._argument_specs("f8(c16[::1])")


def test_a_built_kernel_is_never_handed_arrays_it_was_not_built_for():
    """The ahead-of-time wrappers read any buffer as the declared type: the check must refuse."""
    calls = []
    contiguous = lambda *a: calls.append("C") or "C"  # noqa: E731
    strided = lambda *a: calls.append("A") or "A"  # noqa: E731
    call = compiled._checked("k", [(contiguous, compiled._argument_specs("f8(f8[:, ::1], f8)")),
                                   (strided, compiled._argument_specs("f8(f8[:, :], f8)"))])
    a = np.zeros((3, 4))
    assert call(a, 1.0) == "C"
    assert call(a[:, ::2], 1.0) == "A"  # a strided view takes the strided build, never the C one
    for bad in (a.astype(np.float32), a[0], a.astype(np.int64), [[0.0]]):
        with pytest.raises(TypeError, match="compiled kernel k has no variant"):
            call(bad, 1.0)
    with pytest.raises(TypeError):
        call(a)  # wrong number of arguments
    assert calls == ["C", "A"]


def test_an_edited_kernel_is_never_served_by_a_stale_build(tmp_path, monkeypatch):
    digest = tmp_path / "_aot_kernels.digest"
    monkeypatch.setattr(compiled, "AOT_DIGEST", digest)
    assert compiled._current_aot() is None  # no digest: not built (or interrupted)
    digest.write_text("0" * 64 + "\n")
    assert compiled._current_aot() is None  # built from other sources
    if importlib.util.find_spec(compiled.AOT_MODULE) is not None:
        digest.write_text(compiled.source_digest() + "\n")
        assert compiled._current_aot() is not None


def test_the_digest_covers_every_kernel_source():
    names = {p.relative_to(compiled.PACKAGE_DIR).as_posix() for p in compiled.kernel_sources()}
    assert {"accel/belief.py", "accel/retained.py", "accel/executors.py", "accel/seeding.py",
            "tasks/insertion/kernels.py", "accel/compiled.py"} <= names
    assert "accel/__init__.py" not in names
    assert "probecommit.tasks.insertion.kernels" in compiled.kernel_modules()


def test_the_mode_can_be_forced_and_a_wrong_one_is_named():
    out = _child("from probecommit.accel import compiled; print(compiled.MODE)", PROBECOMMIT_KERNELS="jit")
    assert out.stdout.strip() == "jit", out.stderr
    out = _child("from probecommit import accel; print(accel.mode(), type(accel.production().filter).__module__)",
                 PROBECOMMIT_KERNELS="numpy")  # the NumPy reference: no kernel module imported
    assert out.stdout.split() == ["numpy", "probecommit.core.belief"], out.stderr
    out = _child("import probecommit.accel.compiled", PROBECOMMIT_KERNELS="fast")
    assert out.returncode != 0 and "PROBECOMMIT_KERNELS='fast': expected one of aot, jit, numba or numpy" in out.stderr


def test_the_build_command_has_help_and_builds_nothing_with_it():
    out = subprocess.run([sys.executable, "-m", "probecommit.accel.compiled", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "Build the compiled kernels ahead of time" in out.stdout
    assert "entry points" not in out.stdout  # the build's own line: nothing was built
    out = subprocess.run([sys.executable, "-m", "probecommit.accel.compiled", "--bogus"], capture_output=True, text=True)
    assert out.returncode == 2 and "unrecognized arguments: --bogus" in out.stderr


aot_only = pytest.mark.skipif(compiled.MODE != "aot", reason="the ahead-of-time kernels are not built here (make kernels)")


@aot_only
def test_the_built_kernels_run_without_numba_or_llvm():
    out = _child("import sys; from probecommit.accel import compiled, executors; from probecommit.tasks.insertion import kernels;"
                 "print(compiled.MODE, sorted(m for m in sys.modules if m.split('.')[0] in ('numba', 'llvmlite')))")
    assert out.stdout.strip() == "aot []", out.stderr


@aot_only
def test_a_built_kernel_refuses_a_strided_array_where_it_needs_a_contiguous_one():
    lo = np.zeros((4, 6))
    mask = np.ones((4, 3), dtype=bool)
    with pytest.raises(TypeError, match="strided"):
        executors._interval_counts(lo[:, ::2], lo[:, ::2], mask, np.linspace(0.0, 1.0, 5))


@aot_only
@pytest.mark.slow
def test_the_jit_kernels_pass_the_same_tests_as_the_built_ones():
    """The build is made from the numba functions; both must agree with the NumPy reference."""
    tests = ["tests/accel/test_agreement.py", "tests/core/test_belief.py", "tests/tasks/insertion/test_model.py"]
    full = dict(os.environ)
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *tests],
                         env={**full, "PROBECOMMIT_KERNELS": "jit"}, capture_output=True, text=True, timeout=900,
                         cwd=compiled.PACKAGE_DIR.parents[1])
    assert out.returncode == 0, out.stdout[-3000:]
    assert " passed" in out.stdout


def test_help_loads_neither_the_kernels_nor_numba():
    """``probecommit --help`` computes nothing: no kernel module, no numba (its start-up target)."""
    # Read at exit (an atexit handler: the command ends the process itself once it has run them).
    out = _child("import atexit, runpy, sys\n"
                 "atexit.register(lambda: print('LOADED', sorted(m for m in sys.modules if m.split('.')[0] in "
                 "('numba', 'llvmlite') or m.startswith('probecommit.accel.') or m == 'probecommit._aot_kernels')))\n"
                 "sys.argv = ['probecommit', '--help']\n"
                 "runpy.run_module('probecommit', run_name='__main__')\n")
    assert out.stdout.splitlines()[-1] == "LOADED []", out.stdout[-2000:] + out.stderr[-2000:]
