# The README's commands. Every target sets up its own virtual environment first.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test test-nightly lint format bench lock lock-upgrade lock-check clean

# The libraries come from requirements-dev.lock, each at its pinned version and checked
# against its hashes (pip refuses any library the lock does not pin); calstation itself
# is then installed on top of them, without dependencies of its own choosing.
$(STAMP): pyproject.toml requirements-dev.lock
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --require-hashes -r requirements-dev.lock
	$(PY) -m pip install --quiet --no-deps -e .
	touch $(STAMP)

# The lock files: every library of every platform's install, pinned with its hashes, for
# Python 3.11 and later (uv pip compile --universal). `make lock` keeps every pin that
# still fits pyproject.toml; `make lock-upgrade` takes the newest that fit.
LOCK := $(VENV)/bin/uv pip compile pyproject.toml --universal --python-version 3.11 \
	--generate-hashes --custom-compile-command 'make lock' --quiet $(LOCK_FLAGS)

lock: $(STAMP)  ## regenerate requirements.lock (the image) and requirements-dev.lock (.venv, CI)
	$(LOCK) -o requirements.lock
	$(LOCK) --extra dev -o requirements-dev.lock

lock-upgrade:  ## regenerate the lock files with the newest versions pyproject.toml allows
	$(MAKE) lock LOCK_FLAGS=--upgrade

lock-check: $(STAMP)  ## the lock files pin what pyproject.toml asks for (CI runs it first)
	$(PY) -m pytest -q -n 0 -p no:cacheprovider tests/test_lock.py

demo: $(STAMP)  ## the main job on the embedded defaults
	$(VENV)/bin/calstation demo

# The suite starts some two hundred Python processes (stations, servers, commands) and
# rewrites its test modules' asserts in each worker: with PYTHONDONTWRITEBYTECODE set (as
# on some CI images) each of them compiled everything again, 5 s of CPU a worker.
test: $(STAMP)  ## the whole test suite, two workers per core (tests/conftest.py; -n 0 for one process)
	@start=$$(date +%s); env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest -n auto --durations=15; status=$$?; \
	echo "make test: $$(( $$(date +%s) - start )) s wall, exit $$status"; exit $$status

test-nightly: $(STAMP)  ## the whole suite at the nightly sizes of its properties and API fuzzing
	HYPOTHESIS_PROFILE=nightly $(MAKE) test

lint: $(STAMP)  ## ruff (lint and format check), strict mypy and the import contracts (layers)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports

format: $(STAMP)
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

bench: $(STAMP)  ## every benchmark in benchmarks/ (minutes; results go to docs/benchmarks.md by hand)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache .import_linter_cache
