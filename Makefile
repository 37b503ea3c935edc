# probegen — see README.md.  Everything runs from a venv in .venv, made on first use.
# BIN and STAMP may be given on the command line: tests/test_readme_tour.py runs
# `make demo BIN=<folder with a probegen shim> STAMP=<an up-to-date file>` (no venv made).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test fuzz goldens lint typecheck bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/probegen compile samples/sphere25/sphere_test.toml -d fanuc -d dmis -o out
	$(BIN)/probegen sphere-points --layout octahedral
	@echo "== the virtual machine runs out/sphere_test.nc with the sphere 1.2, -0.9, 0.4 mm off nominal"
	@echo "   and a lobing probe, and sends what it prints over a pseudo-terminal to probegen capture"
	rm -f out/run.log
	$(BIN)/probegen sim out/sphere_test.nc --spec samples/sphere25/sphere_test.toml \
	    --offset 1.2 -0.9 0.4 --lobing 0.0012 0.0008 0.0005 --pty out/vm.tty --pty-delay 3 & \
	    sleep 2; $(BIN)/probegen capture --port out/vm.tty --out out/run.log --timeout 20; wait
	$(BIN)/probegen ingest out/run.log --spec samples/sphere25/sphere_test.toml -o out --write-calibration out/probe-calibration.toml
	$(BIN)/probegen report out/results.json -o out/report.html
	@echo "programs: out/sphere_test.nc (Fanuc Macro B, compact: calls the macro library out/O8000.nc-O8002.nc), out/sphere_test.dmi (DMIS)"
	@echo "machine log: out/run.log; results: out/results.json, out/results.csv, out/probe-calibration.toml"
	@echo "report: out/report.html"

# JOBS: pytest-xdist workers (auto: one per core); each test file runs whole on one worker.
JOBS ?= auto
test: $(STAMP)
	$(BIN)/python -m pytest -n $(JOBS) --dist loadfile
	$(BIN)/lint-imports
	$(BIN)/ruff check probegen tests benchmarks samples
	$(BIN)/mypy probegen

# The property-based tests, long and random (tests/fuzzing.py); FACTOR scales the examples.
FACTOR ?= 20
fuzz: $(STAMP)
	PROBEGEN_HYPOTHESIS=fuzz PROBEGEN_FUZZ_FACTOR=$(FACTOR) $(BIN)/python -m pytest -q \
	    $$(grep -l '@given' tests/test_*.py)

goldens: $(STAMP)
	PROBEGEN_REGEN=1 $(BIN)/python -m pytest -q $$(grep -l 'assert_golden\|REGEN' tests/test_*.py)
	git status --short tests

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_sphere_test.py

clean:
	rm -rf $(VENV) out build dist *.egg-info .pytest_cache .mypy_cache .ruff_cache .hypothesis .import_linter_cache
