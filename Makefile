# One command sets up and runs the operator console server on the simulated rig: `make run`.
# One command sets up and runs every check CI runs: `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
HOST ?= 127.0.0.1
PORT ?= 8080
DATA ?= ./tmeye-data

.PHONY: setup run track test lint typecheck dbcheck unit clean

$(STAMP): pyproject.toml
	@$(PY) -c "import venv, ensurepip" 2>/dev/null || (apt-get update && apt-get install -y python3-venv)
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/tmeye serve --host $(HOST) --port $(PORT) --data-dir $(DATA)

track: $(STAMP)
	$(BIN)/tmeye track --source sim --scenario walk

lint: $(STAMP)
	$(BIN)/ruff check tracker calibration tmeye server alembic tests

typecheck: $(STAMP)
	$(BIN)/mypy tracker calibration tmeye server

# The migrations build an empty database to head and match the models (no drift).
dbcheck: $(STAMP)
	@d=$$(mktemp -d) && $(BIN)/alembic -x data_dir=$$d upgrade head >/dev/null 2>&1 && \
	$(BIN)/alembic -x data_dir=$$d check; s=$$?; rm -rf $$d; exit $$s

unit: $(STAMP)
	$(BIN)/pytest

test: lint typecheck dbcheck unit

clean:
	rm -rf $(VENV) build *.egg-info
