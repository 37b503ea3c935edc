# probegen — see README.md.  Everything runs from a venv in .venv, made on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test goldens lint typecheck bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/probegen compile samples/sphere25/sphere_test.toml -d fanuc -d dmis -o out
	$(BIN)/probegen sphere-points --layout octahedral
	$(BIN)/probegen ingest samples/sphere25/sphere_test.log --spec samples/sphere25/sphere_test.toml -o out --write-calibration out/probe-calibration.toml
	@echo "programs written under out/: out/sphere_test.nc (Fanuc Macro B), out/sphere_test.dmi (DMIS)"
	@echo "results of the sample log under out/: results.json, results.csv, probe-calibration.toml"

test: $(STAMP)
	$(BIN)/python -m pytest
	$(BIN)/ruff check probegen tests benchmarks samples
	$(BIN)/mypy probegen

goldens: $(STAMP)
	PROBEGEN_REGEN=1 $(BIN)/python -m pytest -q tests/test_golden.py tests/test_bad_inputs.py tests/test_cad.py
	git status --short tests/golden tests/bad_inputs

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_sphere_test.py

clean:
	rm -rf $(VENV) out build dist *.egg-info .pytest_cache .mypy_cache .ruff_cache .hypothesis
