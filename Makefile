# Every target creates and uses .venv/ in the repo root.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: test lint run demo bench results clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint
	$(BIN)/pytest

run: $(STAMP)
	$(BIN)/nemesys console

demo: $(STAMP)
	./scripts/demo.sh

bench: $(STAMP)
	$(BIN)/nemesys bench codec

# docs/results.md and docs/results/: the paper's tables and figures beside ours (full mode).
results: $(STAMP)
	$(BIN)/nemesys results

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
