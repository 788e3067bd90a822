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
# (tests/blas_kernels.py picks them), the two passes side by side (one per core); a pass's
# full output is shown when it fails. Nothing pins a kernel outside these runs.
# THREADS: the tests call the library below its public entry points, where its own thread
# limit (analytic/threads.py) is not applied, and compare round-off-level numbers made with
# one thread (a threaded OpenBLAS may split a sum across threads, another round-off):
# the variables hold them at one thread from the interpreter's start (conftest.py sets the
# same defaults for a bare pytest).
THREADS := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
test: $(STAMP)
	$(THREADS) $(BIN)/python -m pytest tests compare
	@kernels="$$($(BIN)/python tests/blas_kernels.py)"; \
	if [ -z "$$kernels" ]; then \
		echo "numerics under other kernels: skipped (numpy's BLAS is not OpenBLAS on x86-64)"; \
		exit 0; fi; \
	logs=$$(mktemp -d); \
	for k in $$kernels; do \
		(OPENBLAS_CORETYPE=$$k $(THREADS) $(BIN)/python -m pytest -q -m numerics \
			-p no:cacheprovider tests compare > $$logs/$$k.log 2>&1; echo $$? > $$logs/$$k.rc) & \
	done; wait; status=0; \
	for k in $$kernels; do \
		if [ "$$(cat $$logs/$$k.rc)" = 0 ]; then \
			echo "numerics under OPENBLAS_CORETYPE=$$k: $$(tail -n 1 $$logs/$$k.log)"; \
		else cat $$logs/$$k.log; echo "numerics under OPENBLAS_CORETYPE=$$k failed"; status=1; fi; \
	done; rm -rf $$logs; exit $$status

# Each writes benchmarks/results/NAME.json (those the docs quote timings from, see
# docs/benchmarks.md); bench_make, bench_presets and bench_kernels run on their own
# (minutes).
benchmark: $(STAMP)
	for b in solver threads beam mujoco bullet sweep report identify trunks; do \
		OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python benchmarks/bench_$$b.py || exit 1; \
	done
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python benchmarks/bench_beam.py --elements 48 --repeats 5

clean:
	rm -rf $(VENV) $(LOCKVENV) build *.egg-info
