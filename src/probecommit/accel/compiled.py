"""How the kernels of ``probecommit.accel`` run: a module built ahead of time, or numba's JIT.

Kernels are written once, as numba nopython functions (``accel/*.py`` and a family's
``kernels.py``), and decorated here: :func:`kernel` marks an entry point (called from Python,
with the argument types it accepts) and :func:`helper` a function only kernels call. How
they run is chosen once per process, by :data:`MODE`:

``"aot"``
    A C extension (``probecommit._aot_kernels``) that numba's ahead-of-time compiler built
    from these same functions (``make kernels``, run by ``make demo`` and ``make test``; or
    ``python -m probecommit.accel.compiled``). It runs without importing numba or LLVM and
    compiles nothing at start: a process that computes little (a 4-episode run) starts in
    half the CPU time of the JIT's, whose import and first cached load cost ~0.7 s.
    Built for this machine's CPU, with the GIL released around each call (as ``nogil=True``).
    Used only while its recorded digest matches the kernel sources and the CPU: an edited
    kernel is never served by a stale build. numba has deprecated ``pycc``, the compiler
    this uses; when it goes, the JIT below is the production path alone.
``"jit"``
    numba compiles each kernel on first use and caches it on disk (``cache=True``).

Both compile the same source, so they are the same production path; ``tests/accel`` checks it
against the NumPy reference. ``PROBECOMMIT_KERNELS=aot|jit`` forces a mode (``aot`` fails if
there is no current build); ``numpy`` is handled by :func:`probecommit.accel.production`, which
then never imports the kernels.

The ahead-of-time wrappers do not check argument types (a strided array passed as
C-contiguous would be read as garbage), so every entry point here checks each array's
dtype, dimensions and layout against its declared signatures and raises ``TypeError``
when none fits.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import re
from pathlib import Path
from typing import Any, Callable

PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: The ahead-of-time module's import name, and the file beside it that records its digest.
AOT_MODULE = "probecommit._aot_kernels"
AOT_DIGEST = PACKAGE_DIR / "_aot_kernels.digest"
#: A family's kernels live in its own module of this name (the build imports them all).
KERNEL_FILE = "kernels.py"
MODES = ("aot", "jit")


def kernel_files() -> list[Path]:
    """Every kernel module: those of ``accel`` and every family's ``kernels.py``."""
    accel = [p for p in Path(__file__).resolve().parent.glob("*.py") if p.name not in ("__init__.py", "compiled.py")]
    return sorted(accel) + sorted(PACKAGE_DIR.rglob(KERNEL_FILE))


def kernel_sources() -> list[Path]:
    """The files the ahead-of-time build compiles from: every kernel module and this file."""
    return kernel_files() + [Path(__file__).resolve()]


def source_digest() -> str:
    """sha256 over the kernel sources (path relative to the package, then content) and this machine's CPU.

    The build targets the CPU it runs on, so a build copied to another kind of machine is
    not current there either.
    """
    h = hashlib.sha256(_cpu_fingerprint().encode() + b"\0")
    for path in kernel_sources():
        h.update(str(path.relative_to(PACKAGE_DIR)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def _cpu_fingerprint() -> str:
    """The architecture, CPU model and instruction-set flags (Linux), without importing LLVM."""
    import platform

    lines = []
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith(("model name", "flags", "Features", "CPU part")):
                    lines.append(line.strip())
                elif not line.strip() and lines:
                    break  # the first processor is enough
    except OSError:
        pass
    return "\n".join([platform.machine(), platform.processor(), *lines])


def _current_aot() -> Any | None:
    """The built module if it exists and was built from the sources on disk, else None."""
    if importlib.util.find_spec(AOT_MODULE) is None or not AOT_DIGEST.is_file():
        return None
    if AOT_DIGEST.read_text().strip() != source_digest():
        return None
    return importlib.import_module(AOT_MODULE)


def _select() -> tuple[str, Any]:
    """Pick the mode: the environment's choice, else a current build, else numba's JIT."""
    choice = os.environ.get("PROBECOMMIT_KERNELS", "").strip().lower()
    choice = "" if choice in ("numba", "numpy") else choice  # numpy: production() imports no kernel
    if choice and choice not in MODES:
        raise ValueError(f"PROBECOMMIT_KERNELS={choice!r}: expected one of {', '.join(MODES)}, numba or numpy")
    if choice in ("", "aot"):
        module = _current_aot()
        if module is not None:
            return "aot", module
        if choice == "aot":
            raise ImportError(f"PROBECOMMIT_KERNELS=aot, but {AOT_MODULE} is not built from the current kernel sources: "
                              "run `make kernels` (or python -m probecommit.accel.compiled)")
    import numba

    return "jit", numba


MODE, _BACKEND = _select()
#: Entry points declared so far, as (function, signatures): what the build exports.
ENTRIES: list[tuple[Callable[..., Any], tuple[str, ...]]] = []


def helper(inline: bool = False) -> Callable[[Callable[..., Any]], Any]:
    """Decorate a function that only kernels call (``inline``: always inlined into them).

    In an ahead-of-time process the build has already compiled it into its callers, so the
    Python function is returned unchanged and never called.
    """
    if MODE == "aot":
        return lambda func: func
    options = {"inline": "always"} if inline else {}
    return _BACKEND.njit(cache=True, nogil=True, **options)


def kernel(*signatures: str) -> Callable[[Callable[..., Any]], Any]:
    """Decorate a kernel entry point, with the numba signatures it is built for (one per layout).

    Args:
        *signatures: numba signature strings, e.g. ``"i8[:, ::1](f8[:, ::1], f8)"``, in the
            order they are tried (put the C-contiguous one first).

    Returns:
        In ``jit`` mode a lazily compiling numba dispatcher; in ``aot`` mode the built
        function behind a type check.
    """
    if not signatures:
        raise ValueError("a kernel needs at least one signature")

    def wrap(func: Callable[..., Any]) -> Any:
        if MODE == "jit":
            ENTRIES.append((func, signatures))
            return _BACKEND.njit(cache=True, nogil=True)(func)
        variants = [(getattr(_BACKEND, export_name(func, n)), _argument_specs(sig)) for n, sig in enumerate(signatures)]
        return _checked(func.__qualname__, variants)
    return wrap


def export_name(func: Callable[..., Any], variant: int) -> str:
    """The name a kernel's ``variant``-th signature is exported under in the built module."""
    module = func.__module__.removeprefix("probecommit.").replace(".", "_")
    return f"{module}__{func.__name__.lstrip('_')}__{variant}"


# --- checking arguments against a signature (no numba needed) ---------------------------------

_DTYPES = {"f8": "float64", "float64": "float64", "i8": "int64", "int64": "int64", "b1": "bool", "boolean": "bool",
           "u8": "uint64", "uint64": "uint64", "u4": "uint32", "uint32": "uint32"}
_ARG = re.compile(r"^(\w+)(?:\[(.*)\])?$")


def _split_top(text: str) -> list[str]:
    """Split on commas outside brackets and parentheses."""
    parts, depth, start = [], 0, 0
    for i, char in enumerate(text):
        if char in "[(":
            depth += 1
        elif char in "])":
            depth -= 1
        elif char == "," and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    tail = text[start:].strip()
    return parts + ([tail] if tail else [])


def _argument_specs(signature: str) -> list[tuple[str, int, bool] | None]:
    """Per argument of ``"ret(arg, ...)"``: (dtype, ndim, C-contiguous) for an array, None for a scalar."""
    arguments = _arguments_text(signature)
    specs: list[tuple[str, int, bool] | None] = []
    for text in _split_top(arguments):
        match = _ARG.match(text.replace(" ", ""))
        if match is None or match.group(1) not in _DTYPES:
            raise ValueError(f"signature {signature!r}: cannot read argument {text!r}")
        dims = match.group(2)
        if dims is None:
            specs.append(None)
            continue
        axes = dims.split(",")
        specs.append((_DTYPES[match.group(1)], len(axes), axes[-1] == "::1"))
    return specs


def _arguments_text(signature: str) -> str:
    """The text between the parentheses of the argument list (the last top-level group)."""
    depth = 0
    for i in range(len(signature) - 1, -1, -1):
        char = signature[i]
        if char in ")]":
            depth += 1
        elif char in "([":
            depth -= 1
            if depth == 0 and char == "(":
                return signature[i + 1:-1]
    raise ValueError(f"signature {signature!r} has no argument list")


def _fits(args: tuple[Any, ...], specs: list[tuple[str, int, bool] | None]) -> bool:
    if len(args) != len(specs):
        return False
    for value, spec in zip(args, specs):
        if spec is None:
            continue
        dtype, ndim, contiguous = spec
        if (getattr(value, "ndim", None) != ndim or getattr(value, "dtype", None) != dtype
                or (contiguous and not value.flags.c_contiguous)):
            return False
    return True


def _checked(name: str, variants: list[tuple[Callable[..., Any], list]]) -> Callable[..., Any]:
    """Call the first built variant whose argument types fit, else raise (never read garbage)."""
    def call(*args: Any) -> Any:
        for function, specs in variants:
            if _fits(args, specs):
                return function(*args)
        got = ", ".join(f"{a.dtype}[{a.ndim}d{'' if a.flags.c_contiguous else ', strided'}]" if hasattr(a, "dtype")
                        else type(a).__name__ for a in args)
        raise TypeError(f"compiled kernel {name} has no variant for ({got})")
    call.__name__ = call.__qualname__ = name
    return call


# --- the ahead-of-time build ------------------------------------------------------------------

def kernel_modules() -> list[str]:
    """Import names of every kernel module of the package."""
    return [".".join(path.relative_to(PACKAGE_DIR.parent).with_suffix("").parts) for path in kernel_files()]


def build() -> Path:
    """Compile every kernel entry point into ``probecommit._aot_kernels`` with numba's AOT compiler.

    Runs in a process whose kernels are in ``jit`` mode (the module is built from the numba
    functions themselves); writes the digest last, so an interrupted build is never used.

    Returns:
        The folder of the built module and its digest (the package's own).
    """
    if MODE != "jit":
        raise RuntimeError(f"the build needs numba's functions: run it with PROBECOMMIT_KERNELS=jit (mode is {MODE})")
    import warnings

    for name in kernel_modules():
        importlib.import_module(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numba.pycc's deprecation notice
        from numba.pycc import CC

        import numba.pycc.compiler as pycc_compiler

        cc = CC(AOT_MODULE.rsplit(".", 1)[1])
        cc.output_dir = str(PACKAGE_DIR)
        cc.verbose = False
        cc.target_cpu = "host"  # as the JIT does (numba's AOT default is a generic x86-64: slower)
        for func, signatures in ENTRIES:
            for n, signature in enumerate(signatures):
                cc.export(export_name(func, n), signature)(func)
        digest = source_digest()
        AOT_DIGEST.unlink(missing_ok=True)
        # The exported wrappers release the GIL around the compiled call, as the JIT kernels do
        # (nogil=True): unit threads run kernels in parallel. pycc has no option for it; its
        # flags object is swapped for the duration of the build.
        plain_flags = pycc_compiler.Flags
        pycc_compiler.Flags = _nogil_flags(plain_flags)
        try:
            cc.compile()
        finally:
            pycc_compiler.Flags = plain_flags
    AOT_DIGEST.write_text(digest + "\n")
    return PACKAGE_DIR


def _nogil_flags(flags_class: type) -> type:
    """numba's compiler flags with ``release_gil`` set (what ``njit(nogil=True)`` sets)."""
    class NoGilFlags(flags_class):  # type: ignore[misc, valid-type]
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self.release_gil = True
    return NoGilFlags


def main(argv: list[str] | None = None) -> None:
    """``python -m probecommit.accel.compiled``: build the ahead-of-time module (in a JIT-mode child)."""
    import argparse
    import subprocess
    import sys
    import time

    argparse.ArgumentParser(
        prog="python -m probecommit.accel.compiled",
        description=f"Build the compiled kernels ahead of time into {AOT_MODULE} for this machine's CPU "
                    "(needs numba and a C compiler; `make kernels` runs it). Until it is rebuilt after a "
                    "kernel source changes, numba's JIT runs the kernels.").parse_args(argv)
    if os.environ.get("PROBECOMMIT_KERNELS") != "jit":
        env = {**os.environ, "PROBECOMMIT_KERNELS": "jit"}
        raise SystemExit(subprocess.call([sys.executable, "-m", "probecommit.accel.compiled"], env=env))
    # Run as __main__, this file is a second copy of the module: the kernels register with the
    # imported one, so build through it.
    from probecommit.accel import compiled

    start = time.perf_counter()
    try:
        out = compiled.build()
    except Exception as error:  # a missing compiler or numba: one line, and the JIT stays in use
        raise SystemExit(f"could not build {AOT_MODULE}: {type(error).__name__}: {error}") from None
    print(f"built {AOT_MODULE} ({sum(len(s) for _, s in compiled.ENTRIES)} entry points) into {out} "
          f"in {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
