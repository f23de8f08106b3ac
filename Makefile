# planthub — every target sets up what it needs on a machine with only Python 3.11, gcc and make.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
SCENARIO ?= scenarios/bottling_plant.yaml
# make view: the run's name (its scenario's name, here its file's), where its hub listens, the page's port
RUN       ?= $(basename $(notdir $(SCENARIO)))
VIEW_BUS  ?= tcp/127.0.0.1:7447
VIEW_PORT ?= 8765
VIEW_STAMP := build/view/.built
VIEW_SOURCES := hub/view/web/package-lock.json hub/view/web/package.json hub/view/web/build.mjs \
                hub/view/web/index.html $(shell find hub/view/web/src -type f 2>/dev/null)
CHROMIUM := /usr/bin/chromium
WARM     := build/.warm
TEST_WORKERS ?= $(shell echo $$(( $$(nproc) + 1 )))

.PHONY: run test bench stability screenshot fmus venv view view-assets chromium warm clean clean-venv

run: $(STAMP) fmus view-assets $(WARM)
	$(PY) -m hub run $(SCENARIO)

# The lint (ruff, pyproject.toml's [tool.ruff]) and the suite on a worker more than the cores
# (pytest-xdist: each test file whole on one worker), ending with its slowest tests. `-m "not slow"`
# leaves out the plant runs. The extra worker fills the time tests wait (browsers, launched processes,
# wall-clock limits): a quarter of the tests' wall time, when a core stood idle; on 2 cores the suite
# took 5:24 and 5:30 with 3 workers, 5:59 and 6:05 with 2. TEST_WORKERS=N sets another number.
# Bytecode is written (into __pycache__, ignored by git) even where PYTHONDONTWRITEBYTECODE is set: the
# suite starts a Python process for every command it tries, and each would compile the hub's sources again.
test: $(STAMP) fmus view-assets chromium $(WARM)
	$(PY) -m ruff check --quiet hub modules tests fmus
	env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest -n $(TEST_WORKERS) --dist loadfile --durations=15

# The physics tick's compiled loops (numba, cached beside their sources in __pycache__) compiled
# once at set-up, so that a fresh clone's first run is as fast as its second: 20 s of the bottling
# plant call every one of them (about 30 s here the first time, a few seconds after).
warm: $(WARM)

$(WARM): $(STAMP) $(wildcard hub/physics/*.py) | fmus
	@mkdir -p build; echo "compiling the physics tick's loops (once; numba keeps them)"
	@$(PY) -m hub run scenarios/bottling_plant.yaml -q --set run.duration=20 --out build/warm > build/warm.log 2>&1 \
	    || { cat build/warm.log; exit 1; }
	@touch $@

# The bottling plant at real time with its view beside it: open the address it prints. Ctrl-C ends both
# (each gets it; the run writes its files and summary so far); when the view fails, the run is ended too.
view: $(STAMP) fmus view-assets
	@$(PY) -m hub run $(SCENARIO) --realtime --listen $(VIEW_BUS) & hub=$$!; \
	$(PY) -m hub view $(RUN) --connect $(VIEW_BUS) --port $(VIEW_PORT); status=$$?; \
	case $$status in 130|143) ;; *) kill -TERM $$hub 2>/dev/null ;; esac; \
	wait $$hub; exit $$status

# The browser front-end of `planthub view` (hub/view/web/, esbuild) into build/view/: rebuilt only
# when its lock file, its build script or its sources change.
view-assets: $(VIEW_STAMP)

$(VIEW_STAMP): $(VIEW_SOURCES)
	@echo "building the view's page (npm ci, esbuild)"
	@cd hub/view/web && npm ci --no-audit --no-fund --loglevel=error && npm run --silent build
	@touch $@

# The browser the view's test drives (Playwright launches it; it never downloads one of its own).
chromium: $(CHROMIUM)

$(CHROMIUM):
	apt-get update && apt-get install -y --no-install-recommends chromium

# One report: build/bench/report.md with its plots and report.json (tests/bench_report.py); under 20 min here.
bench: $(STAMP) fmus view-assets chromium
	$(PY) -m tests.bench_report

# The long hard cases (tests/hard/): 10 simulated minutes of a jam, an hour of the paper's loop and of
# the bottling plant, each against its stated bounds, side by side on a LocalCluster (one worker a core);
# results to build/bench/stability.json for the report.
stability: $(STAMP) fmus
	$(PY) -m tests.hard.stability

# The README's picture of the view (hub/view/bottling_plant.png): the bottling plant at real time on
# loopback with `planthub view`, shot in headless chromium once about 40 bottles are on the line.
screenshot: $(STAMP) fmus view-assets chromium
	$(PY) -m tests.screenshot_view hub/view/bottling_plant.png

fmus: $(STAMP)
	@if [ -f fmus/Makefile ]; then $(MAKE) -s -j$(shell nproc) --no-print-directory -C fmus PYTHON=$(abspath $(PY)) BUILD=$(abspath build/fmus); fi

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
