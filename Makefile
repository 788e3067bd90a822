# The two commands of the README: `make report` (the main job) and `make test`.
# Both create .venv when it is missing and install the project into it.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= reports

.PHONY: report test benchmark lock clean

# Every package comes from requirements.lock (pip and setuptools included), then the project
# itself without dependencies; `make lock` refreshes the lock from pyproject.toml's ranges.
# PYTHONWARNINGS silences only setuptools' note that an editable install is editable.
$(STAMP): pyproject.toml requirements.lock
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet "$$(grep '^pip==' requirements.lock)"
	$(BIN)/python -m pip install --quiet -r requirements.lock
	@# A venv upgraded from the one-package mujoco 3.x loses mujoco-core's files to the old
	@# package's uninstall (one shared folder): reinstall the three when the import fails.
	$(BIN)/python -c "import mujoco" 2>/dev/null || $(BIN)/python -m pip install --quiet \
		--force-reinstall --no-deps $$(grep -E '^mujoco(-core|-studio)?==' requirements.lock)
	PYTHONWARNINGS="ignore:Editable installation" $(BIN)/python -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $(STAMP)

# The lock: `uv pip compile` (uv pinned here, in a venv of its own) over pyproject.toml with
# the test extra, plus pip and the build backend; one set of versions for Python 3.11-3.13.
UV_VERSION := 0.13.9
LOCKVENV   := .lockvenv
lock:
	test -x $(LOCKVENV)/bin/uv || ($(PYTHON) -m venv $(LOCKVENV) && $(LOCKVENV)/bin/python -m pip install --quiet uv==$(UV_VERSION))
	printf 'pip\nsetuptools>=77\n' | $(LOCKVENV)/bin/uv pip compile pyproject.toml - --extra test \
		--universal --fork-strategy fewest --python-version 3.11 --custom-compile-command "make lock" \
		--quiet -o requirements.lock

# The discrepancy report with the default model-validity study as one of its sections:
# $(OUT)/report.html, report.md, report.json; the study in $(OUT)/study and the design map
# in $(OUT)/design, run beside the report's own runs (--with-study: child processes, so none
# leaves a core idle). The pages link their figures (PNG files in $(OUT)/figures,
# $(OUT)/study and $(OUT)/design): move the folder whole.
# No OPENBLAS_NUM_THREADS: the command and its workers limit BLAS threads themselves
# (analytic/threads.py, docs/reproducibility.md "BLAS threads").
report: $(STAMP)
	rm -rf $(OUT)/study $(OUT)/design  # fresh studies: rows resumed from an older code version would be stale
	$(BIN)/treeimpact report --out $(OUT) --with-study default --with-study design

# The whole suite on this machine's BLAS kernel, then the tests marked numerics (BLAS
# round-off: conftest.py NUMERICS) under two other machines' OpenBLAS kernels
# (tests/blas_kernels.py picks them). Nothing pins a kernel outside these runs. The kernel
# passes collect only the NUMERICS files among TESTS (conftest.numerics_files; no other file
# may hold the mark): collecting the whole suite to deselect all but these cost each pass
# about 5 CPU-seconds of imports.
# The main suite runs on pytest-xdist, one worker per core the process may use (WORKERS;
# `make test WORKERS=0` runs it serially in one process): serial, one core sat idle for its
# ~6 minutes (benchmarks/results/floors.json). --dist loadgroup (conftest.py's scheduler:
# SESSION_FILES, MODULE_FIXTURE_FILES) keeps each file whose tests share a module fixture on
# one worker, and every test of the session's ladder runs on one: each made once, not once
# per worker, the largest group first; the other tests spread one by one.
# The two kernel passes (one process each) start first, beside it, under `nice`: they take
# what the suite's workers leave idle (its start, the waits of its signal and time-out
# tests, its last file) and cost its timing-sensitive tests little; a pass's full output is
# shown when it fails, and make test fails when any of the three does.
# THREADS: the tests call the library below its public entry points, where its own thread
# limit (analytic/threads.py) is not applied, and compare round-off-level numbers made with
# one thread (a threaded OpenBLAS may split a sum across threads, another round-off):
# the variables hold them at one thread from the interpreter's start (conftest.py sets the
# same defaults for a bare pytest). TESTS: the folders or files to run (all by default).
THREADS := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
WORKERS ?= $(shell $(PYTHON) -c 'import os; print(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count())')
TESTS   ?= tests compare
test: $(STAMP)
	@kernels="$$($(BIN)/python tests/blas_kernels.py)"; logs=$$(mktemp -d); pids=; \
	files="$$($(BIN)/python -c 'import sys, conftest; print(*conftest.numerics_files(sys.argv[1:]))' $(TESTS))"; \
	[ -n "$$files" ] || kernels=; \
	trap 'kill $$pids 2>/dev/null; rm -rf $$logs' EXIT; trap 'exit 130' INT TERM; \
	for k in $$kernels; do \
		OPENBLAS_CORETYPE=$$k $(THREADS) nice -n 10 $(BIN)/python -m pytest -q -m numerics \
			-p no:cacheprovider $$files > $$logs/$$k.log 2>&1 & pids="$$pids $$!"; \
	done; \
	$(THREADS) $(BIN)/python -m pytest -n $(WORKERS) --dist loadgroup $(TESTS); status=$$?; \
	[ -n "$$kernels" ] || echo "numerics under other kernels: skipped (numpy's BLAS is not OpenBLAS on x86-64, or TESTS holds no NUMERICS file)"; \
	set -- $$pids; for k in $$kernels; do \
		if wait $$1; then echo "numerics under OPENBLAS_CORETYPE=$$k: $$(tail -n 1 $$logs/$$k.log)"; \
		else cat $$logs/$$k.log; echo "numerics under OPENBLAS_CORETYPE=$$k failed"; status=1; fi; \
		shift; \
	done; pids=; exit $$status

# Each writes benchmarks/results/NAME.json (those the docs quote timings from, see
# docs/benchmarks.md); bench_make, bench_presets and bench_kernels run on their own
# (minutes).
benchmark: $(STAMP)
	for b in solver threads beam mujoco bullet sweep report identify trunks help chatter; do \
		OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python benchmarks/bench_$$b.py || exit 1; \
	done
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python benchmarks/bench_beam.py --elements 48 --repeats 5

clean:
	rm -rf $(VENV) $(LOCKVENV) build *.egg-info
