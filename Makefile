# The two commands of the README. Both run the idempotent bootstrap first.
.PHONY: bootstrap demo test test-fast lint
VENV_BIN := .venv/bin

bootstrap:
	bash scripts/bootstrap.sh

demo: bootstrap
	$(VENV_BIN)/spectwin demo --out out/demo

# The suite's processes (workers, commands, notebook kernels, Dask workers: each imports the
# packages) keep Python's bytecode caches even where the environment turns them off
# (PYTHONDONTWRITEBYTECODE=1, as in many container images): compiled once, not in every process
# (the suite's collection 15.6 s without them, 8.5 s with them; BENCHMARKS.md, "The test suite").
test test-fast: export PYTHONDONTWRITEBYTECODE :=

# The suite on every core (test files spread over worker processes in the order collected: the
# longest first, conftest.py), the 20 slowest shown.
test: bootstrap
	$(VENV_BIN)/python -m pytest -q -n auto --dist loadfile --no-loadscope-reorder --durations=20

# The inner loop: the libraries' unit tests and the architecture and error checks, no renders.
test-fast: bootstrap
	$(VENV_BIN)/python -m pytest -q -n auto --dist loadfile -m "not render and not hardware" \
		tests/recon tests/hwbridge tests/twin/rigs tests/twin/components tests/twin/sensor \
		tests/test_errors.py tests/test_architecture.py recon hwbridge --ignore tests/recon/experiments

lint: bootstrap
	$(VENV_BIN)/ruff check .
