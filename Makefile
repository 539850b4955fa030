# Every target creates and uses .venv/ in the repo root.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# roslibjs and ws for the interop tests (tests/sim_bridge/test_roslibjs.py): node >= 20, npm.
NODE_DIR   := tests/node
NODE_STAMP := $(NODE_DIR)/node_modules/.installed

.PHONY: test lint node-deps run demo bench results clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

$(NODE_STAMP): $(NODE_DIR)/package.json $(NODE_DIR)/package-lock.json
	npm ci --prefix $(NODE_DIR) --no-audit --no-fund
	touch $(NODE_STAMP)

node-deps: $(NODE_STAMP)

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint $(NODE_STAMP)
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
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache $(NODE_DIR)/node_modules
