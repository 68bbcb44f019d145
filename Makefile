# One command sets up and runs the tracker on the simulated rig: `make run`.
# One command sets up and runs every check CI runs: `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup run test lint typecheck unit clean

$(STAMP): pyproject.toml
	@$(PY) -c "import venv, ensurepip" 2>/dev/null || (apt-get update && apt-get install -y python3-venv)
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/tmeye track --source sim --scenario walk

lint: $(STAMP)
	$(BIN)/ruff check tracker calibration tmeye tests

typecheck: $(STAMP)
	$(BIN)/mypy tracker calibration tmeye

unit: $(STAMP)
	$(BIN)/pytest

test: lint typecheck unit

clean:
	rm -rf $(VENV) build *.egg-info
