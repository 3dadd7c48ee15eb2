# Set-up and everyday commands. On a CPU-only machine the default TORCH_SPEC installs the
# locally available CPU build; elsewhere pass e.g. `make setup TORCH_SPEC=torch`.
PYTHON ?= python3
VENV ?= .venv
TORCH_SPEC ?= torch==2.13.0
# optional extras installed with the package; CI adds ray to test the Ray path of `reproduce`
EXTRAS ?= test
BIN := $(VENV)/bin
comma := ,
# one stamp per set of extras: `make test EXTRAS=test,ray,mjx` after `make quickstart` installs
# the extras the first venv lacks
EXTRAS_STAMP := $(VENV)/.extras-$(subst $(comma),-,$(EXTRAS))

.PHONY: setup quickstart test lint bench clean

$(VENV)/.torch:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet "$(TORCH_SPEC)"
	touch $@

$(EXTRAS_STAMP): pyproject.toml $(VENV)/.torch
	$(BIN)/pip install --quiet -e ".[$(EXTRAS)]"
	touch $@

setup: $(EXTRAS_STAMP)

# A new run directory each time: nothing earlier is overwritten. The default agent (cpg-actor
# with its tuned settings) and preset (paper): 500k steps, eval return about 700-1000 and a hop
# height about 0.55 m (README, "Status").
QUICKSTART_STAMP := $(shell date +%Y%m%d-%H%M%S)
QUICKSTART_DIR ?= runs/quickstart-$(QUICKSTART_STAMP)
quickstart: setup
	$(BIN)/cpg-actor train --run-dir $(QUICKSTART_DIR)
	$(BIN)/cpg-actor eval $(QUICKSTART_DIR)

test: setup
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest -q

lint: setup
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks

bench: setup
	$(BIN)/python benchmarks/cpg_step.py

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info
