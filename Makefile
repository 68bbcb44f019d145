# One command sets up and runs the operator console server and its browser console on the simulated
# rig: `make run`.
# One command sets up and runs every check CI runs: `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
HOST ?= 127.0.0.1
PORT ?= 8080
DATA ?= ./tmeye-data

WEB_SRC := $(shell find web/src web/index.html web/vite.config.ts web/tsconfig.json web/openapi.json -type f 2>/dev/null)

.PHONY: setup run track test lint typecheck dbcheck unit web openapi clean

$(STAMP): pyproject.toml constraints.txt
	@$(PY) -c "import venv, ensurepip" 2>/dev/null || (apt-get update && apt-get install -y python3-venv)
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -c constraints.txt -e '.[dev]'
	touch $(STAMP)

# Debian's chromium for the browser tests (Playwright drives it; it never downloads a browser).
/usr/bin/chromium:
	apt-get update && apt-get install -y chromium

# Debian's docker-compose validates docker-compose.yml in the tests (no Docker engine is needed or used).
/usr/bin/docker-compose:
	apt-get update && apt-get install -y docker-compose

# The console: npm packages from the lock file, then tsc and the Vite build into web/dist.
web/node_modules/.package-lock.json: web/package-lock.json
	@command -v npm >/dev/null || { echo "make: npm (Node.js 20.19 or newer) is needed to build web/" >&2; exit 1; }
	cd web && npm ci --no-audit --no-fund
	touch $@

web/dist/index.html: web/node_modules/.package-lock.json $(WEB_SRC)
	cd web && npm run build

web: web/dist/index.html

# The server's OpenAPI document for the console, and the TypeScript types generated from it.
openapi: $(STAMP) web/node_modules/.package-lock.json
	$(BIN)/python -c "import json; from server.app import create_app; from server.settings import Settings; \
	print(json.dumps(create_app(Settings()).openapi(), indent=4, ensure_ascii=False))" > web/openapi.json
	cd web && npm run gen:api

setup: $(STAMP) web /usr/bin/chromium /usr/bin/docker-compose

run: $(STAMP) web
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

unit: $(STAMP) web /usr/bin/chromium /usr/bin/docker-compose
	$(BIN)/pytest

test: lint typecheck dbcheck unit

clean:
	rm -rf $(VENV) build *.egg-info web/dist web/node_modules
