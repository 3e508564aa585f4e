# Two commands do everything on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# The demo installs only what it runs (the package, MuJoCo and the numba kernels); the tests install every extra.
DEMO_STAMP := $(VENV)/.installed-demo
STAMP := $(VENV)/.installed

.PHONY: demo test test-fast bench reproduce clean-venv browser system-packages kernels

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade "pip>=24"

$(DEMO_STAMP): pyproject.toml constraints.txt | $(VENV)/bin/python
	$(PY) -m pip install --quiet -c constraints.txt -e '.[mujoco]'
	touch $(DEMO_STAMP)

$(STAMP): pyproject.toml constraints.txt | $(VENV)/bin/python
	$(PY) -m pip install --quiet -c constraints.txt -e '.[all,test]'
	touch $(STAMP) $(DEMO_STAMP)

# The kernels of probecommit.accel built ahead of time into a C extension (probecommit._aot_kernels): a
# process that computes starts without importing numba or LLVM (about 0.7 s of CPU less than the JIT's
# import and first cached load). Rebuilt when a kernel source changes; where it cannot be built (no C
# compiler) numba's JIT runs the same kernels.
KERNEL_SOURCES := $(wildcard src/probecommit/accel/*.py) $(shell find src/probecommit/tasks -name kernels.py)
AOT_DIGEST := src/probecommit/_aot_kernels.digest

$(AOT_DIGEST): $(KERNEL_SOURCES) | $(DEMO_STAMP)
	$(PY) -m probecommit.accel.compiled || echo "warning: the ahead-of-time kernels could not be built; numba's JIT runs them"

## Build the compiled kernels ahead of time (make demo and make test do it).
kernels: $(AOT_DIGEST)

## Create the venv, install pinned dependencies (MuJoCo and numba only), run the demo study and print its report path.
demo: $(DEMO_STAMP) $(AOT_DIGEST)
	$(VENV)/bin/probecommit demo

# The suite runs in two pytest-xdist workers (CI has two cores). loadgroup keeps the tests marked with one
# xdist_group on one worker: tests/conftest.py groups those that share a fixture built once per module or
# session; the Ray tests (one local cluster at a time) name a group of their own. PARALLEL= runs it in one process.
PARALLEL ?= -n 2 --dist loadgroup

## Create the venv, install every pinned extra, run the whole test suite (slow tests included).
## Two system needs come from Debian's packages, installed here when missing (as root; it says what first):
## Chromium (the HTML reports are checked in a real browser) and software OpenGL (Mesa's EGL/llvmpipe
## and OSMesa: MuJoCo renders the scenes of Fig. 1 and Fig. 3 on the CPU).
test: $(STAMP) $(AOT_DIGEST) system-packages
	$(PY) -m pytest -q $(PARALLEL)
	@echo "browser screenshots of the reports: $(CURDIR)/build/screenshots/"

#: Debian packages the tests and the scene renders use.
SYSTEM_PACKAGES := chromium libegl1 libgl1-mesa-dri libosmesa6

system-packages:
	@missing=""; for p in $(SYSTEM_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -z "$$missing" ]; then exit 0; fi; \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing Debian packages:$$missing (apt-get update, then apt-get install --no-install-recommends)"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null \
	  || echo "warning: could not install$$missing: the browser test or the scene-render tests will skip"; \
	else \
	  echo "missing Debian packages:$$missing (run as root: apt-get install$$missing); the tests that need them will skip"; \
	fi

browser: system-packages

## The suite without tests marked slow.
test-fast: $(STAMP) $(AOT_DIGEST)
	$(PY) -m pytest -q $(PARALLEL) -m "not slow"

## Benchmarks: ratios measured side by side in one run, each printing its target (issue 42's first):
## end to end, MuJoCo overhead, calibrate at E = 3072 and 12288, reproduce all, --workers and Ray,
## aborts at exit; then the belief core, the audit, start-up, writes, sessions. Long (an hour idle).
## BENCH_AGAINST=<git ref> also times that ref where a benchmark can (calibrate, memory, reproduce).
BENCH_AGAINST ?=
AGAINST := $(if $(BENCH_AGAINST),--against $(BENCH_AGAINST),)
bench: $(STAMP) $(AOT_DIGEST)
	$(PY) benchmarks/end_to_end.py
	$(PY) benchmarks/mujoco_overhead.py
	$(PY) benchmarks/calibrate.py $(AGAINST)
	$(PY) benchmarks/calibrate.py --instances 3072
	$(PY) benchmarks/reproduce_all.py
	$(PY) benchmarks/scale.py
	$(PY) benchmarks/replay_aborts.py
	$(PY) benchmarks/startup.py
	$(PY) benchmarks/writes.py
	$(PY) benchmarks/belief.py
	$(PY) benchmarks/audit.py
	$(PY) benchmarks/memory.py $(AGAINST)
	$(PY) benchmarks/reproduce.py $(AGAINST)
	$(PY) benchmarks/session.py

## Every table and figure of the paper (resumable; see probecommit reproduce --list).
reproduce: $(STAMP) $(AOT_DIGEST)
	$(VENV)/bin/probecommit reproduce all

clean-venv:
	rm -rf $(VENV)
