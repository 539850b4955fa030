# Every target creates and uses .venv/ in the repo root.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# The interop tests' Node clients (roslibjs and ws: tests/rosbridge/test_roslibjs.py;
# @foxglove/ws-protocol and protobufjs: tests/backend/foxglove_live/test_interop.py): node >= 20, npm.
NODE_DIR   := tests/node
NODE_STAMP := $(NODE_DIR)/node_modules/.installed
# The page's chart (Leaflet) and plots (uPlot), served by the console at /vendor/: no CDN at sea.
VENDOR_DIR   := frontend/vendor
VENDOR_STAMP := $(VENDOR_DIR)/node_modules/.installed

.PHONY: test test-fast test-vehicle lint node-deps vendor vendor-optional run demo bench results clean

# The tests start ~80 Python subprocesses (consoles, simulators, onboard agents) and pytest
# rewrites every test module: with bytecode caching off (a shell or sandbox exporting this),
# each of them compiles the project again (collection alone: 5 s instead of 1.4 s).
unexport PYTHONDONTWRITEBYTECODE

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

$(NODE_STAMP): $(NODE_DIR)/package.json $(NODE_DIR)/package-lock.json
	npm ci --prefix $(NODE_DIR) --no-audit --no-fund
	touch $(NODE_STAMP)

node-deps: $(NODE_STAMP)

$(VENDOR_STAMP): $(VENDOR_DIR)/package.json $(VENDOR_DIR)/package-lock.json
	npm ci --prefix $(VENDOR_DIR) --no-audit --no-fund
	touch $(VENDOR_STAMP)

vendor: $(VENDOR_STAMP)

# `make run` starts the console without them (no npm, no network): the page says why the
# chart and the plots are missing.
vendor-optional:
	@if command -v npm >/dev/null 2>&1 && $(MAKE) --no-print-directory $(VENDOR_STAMP); then :; else \
	  echo "WARNING: the chart and the telemetry plots are unavailable: 'npm ci --prefix $(VENDOR_DIR)'" \
	       "needs npm (node >= 20) and the npm registry once; the console starts without them." >&2; fi

# mypy twice: the project at 3.11 (pyproject.toml), then the vehicle side (its packages, the
# ROS 2 node, their tests: tests/vehicle_side.py) at 3.10, the Python of ROS 2 Humble.
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/mypy --python-version 3.10 --no-warn-unused-configs $$($(BIN)/python -m tests.vehicle_side)

# The whole suite, what CI runs: two workers (pytest-xdist, one per core of a developer's
# 2-core machine); a test module stays on one worker (module-scoped fixtures: one browser, one
# analysis run per module). The tests bind port 0 or a free port, never a fixed one.
test: lint test-vehicle $(NODE_STAMP) $(VENDOR_STAMP)
	$(BIN)/pytest -n 2 --dist loadfile

# The vehicle side's tests (tests/vehicle_side.py) on the Pythons of ROS 2 Humble (3.10) and
# Jazzy (3.12), each in a venv holding only what a vehicle installs (vehicle/pyproject.toml)
# and the tests' tools: scripts/test_vehicle.sh. No such Python is an error saying how to get
# one (.ci/run installs them with pyenv). About 30 s each (1,797 tests) on a busy 2-core
# machine, 10-15 s more when it builds a venv (first run, or vehicle/pyproject.toml changed).
VEHICLE_PYTHONS := 3.10 3.12

test-vehicle:
	@for version in $(VEHICLE_PYTHONS); do ./scripts/test_vehicle.sh $$version || exit 1; done

# The fast tier (about 30 s): unit tests and API tests on the light app (an in-memory vehicle
# link, tests/agent_link.py); no browser, no third-party interop client, no fuzzer, no whole
# console, nothing marked slow (tests/conftest.py). No lint: `make lint` is its own target.
test-fast: $(STAMP)
	$(BIN)/pytest -m "not slow" -n 2 -q

run: $(STAMP) vendor-optional
	$(BIN)/nemesys console

demo: $(STAMP)
	./scripts/demo.sh

bench: $(STAMP)
	$(BIN)/nemesys bench codec

# docs/results.md and docs/results/: the paper's tables and figures beside ours (full mode).
results: $(STAMP)
	$(BIN)/nemesys results

clean:
	rm -rf $(VENV) .venv-vehicle310 .venv-vehicle312 .pytest_cache .mypy_cache .ruff_cache $(NODE_DIR)/node_modules $(VENDOR_DIR)/node_modules
