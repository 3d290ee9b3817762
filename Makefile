# Quick start: `make demo`, `make test`. Both create .venv on first use.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench bytecode lint format clean

# setuptools' editable finder always adds a note on folders named like the package: there is none
# (the sources live in kinematics/, codegen/, app/, infra/, ... mapped under accugrid), so that one note is muted.
$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	PYTHONWARNINGS='ignore:Editable installation' $(BIN)/python -m pip install --quiet -e '.[test,lint]'
	$(MAKE) --no-print-directory bytecode
	touch $(STAMP)

# The editable install imports from these folders; with PYTHONDONTWRITEBYTECODE set (as on
# these machines) every command would compile them again: write their bytecode once.
bytecode:
	$(BIN)/python -m compileall -q __init__.py codegen compensation kinematics app infra

demo: $(STAMP)
	PATH=$(CURDIR)/$(BIN):$$PATH sh examples/demo.sh

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP) bytecode
	$(BIN)/python bench/run.py $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff format .
	$(BIN)/ruff check --fix .

clean:
	rm -rf $(VENV) out .pytest_cache .hypothesis
