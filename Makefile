# The two commands of the README. Both run the idempotent bootstrap first.
.PHONY: bootstrap demo test lint
VENV_BIN := .venv/bin

bootstrap:
	bash scripts/bootstrap.sh

demo: bootstrap
	$(VENV_BIN)/spectwin demo --out out/demo

test: bootstrap
	$(VENV_BIN)/python -m pytest -q

lint: bootstrap
	$(VENV_BIN)/ruff check .
