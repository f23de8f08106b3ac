# planthub — every target sets up what it needs on a machine with only Python 3.11, gcc and make.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SCENARIO ?= scenarios/bottling_plant.yaml

.PHONY: run test bench fmus venv clean clean-venv

run: $(STAMP) fmus
	$(PY) -m hub run $(SCENARIO)

test: $(STAMP) fmus
	$(PY) -m pytest

bench: $(STAMP) fmus
	$(PY) -m tests.bench
	$(PY) -m tests.fmus.bench_petri

fmus: $(STAMP)
	@if [ -f fmus/Makefile ]; then $(MAKE) --no-print-directory -C fmus PYTHON=$(abspath $(PY)) BUILD=$(abspath build/fmus); fi

venv: $(STAMP)

# The environment is rebuilt whenever the pins change.
$(STAMP): requirements.txt pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps -e .
	touch $@

clean:
	rm -rf build runs .pytest_cache

clean-venv: clean
	rm -rf $(VENV)
