# Two set-up commands on a fresh machine (see README):
#   make demo   -- install into .venv and run the main job end to end (SQLite, bundled fixtures)
#   make test   -- install into .venv (with test extras) and run the whole test suite
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= jointdb-demo-output

.PHONY: demo test install clean bench

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

install: $(BIN)/python
	$(BIN)/python -m pip install --quiet ".[test]"

demo: install
	cd /tmp && OPENBLAS_NUM_THREADS=1 $(abspath $(BIN))/jointdb demo --out $(abspath $(OUT))

# PYTHONDONTWRITEBYTECODE is cleared for the test run: with it set, every worker and every `python -m jointdb`
# the tests start would compile (and pytest assertion-rewrite) the same modules again, ~5 s of CPU per worker.
test: install
	PYTHONDONTWRITEBYTECODE= OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/pytest -q -p no:cacheprovider -n auto --dist loadfile --no-loadscope-reorder tests

bench: install
	for f in bench/bench_*.py; do echo "== $$f"; OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info $(OUT)
