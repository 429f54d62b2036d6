# Two commands do all set-up from a fresh clone: `make run` and `make test`.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= out
SCENE ?= synth:crossing
# processes that share the suite (pytest-xdist): two halve its time on a 2-core machine; `0` runs
# it in this process
TEST_WORKERS ?= 2

.PHONY: run test test-fast bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# the video extra (PyAV: fast WebM) is optional: without a wheel for this platform, OpenCV writes
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e ".[video]" || $(BIN)/python -m pip install -q -e .
	touch $@

$(VENV)/.dev-installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $(VENV)/.installed $@

run: $(VENV)/.installed
	$(BIN)/motiontrack track $(SCENE) -o $(OUT) --force

test: $(VENV)/.dev-installed
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS)

# everything but the tests marked slow (end-to-end runs, real-data scores): about a minute
test-fast: $(VENV)/.dev-installed
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) -m "not slow"

bench: $(VENV)/.dev-installed
	$(BIN)/python benchmarks/throughput.py

clean:
	rm -rf $(OUT) build *.egg-info src/*.egg-info
