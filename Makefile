# The two commands of the README: `make report` (the main job) and `make test`.
# Both create .venv when it is missing and install the project into it.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= reports

.PHONY: report test benchmark clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

# The discrepancy report with the default model-validity study as one of its sections:
# $(OUT)/report.html (self-contained), report.md, report.json; the study in $(OUT)/study.
report: $(STAMP)
	rm -rf $(OUT)/study  # a fresh study: rows resumed from an older code version would be stale
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/treeimpact sweep --preset default --out $(OUT)/study
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/treeimpact report --out $(OUT) --study $(OUT)/study

test: $(STAMP)
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python -m pytest tests compare

benchmark: $(STAMP)
	for b in solver mujoco bullet sweep report; do \
		OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python benchmarks/bench_$$b.py || exit 1; \
	done

clean:
	rm -rf $(VENV) build *.egg-info
