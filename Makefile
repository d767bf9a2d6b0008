# Two commands on a fresh machine with Python 3.11 and pip: `make run` and `make test`.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
PIP := $(BIN)/python -m pip

.PHONY: run test lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# The core alone: what the kernel build needs, so `make .venv/.kernels` (or `make -j`) works on its own.
$(VENV)/.installed-core: pyproject.toml | $(BIN)/python
	$(PIP) install -q -e .
	touch $@

$(VENV)/.installed-gui: pyproject.toml | $(BIN)/python
	$(PIP) install -q -e ".[gui]"
	touch $@

$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(PIP) install -q -e ".[dev]"
	touch $@

# The segmentation kernels (ursim_core/segmentation/maoris/csrc) and the planar matcher's loop
# (ursim_core/matching/csrc) are C, compiled into extension modules on first use: do it once here
# rather than inside the first segmentation or match (or in both test workers at once).
$(VENV)/.kernels: $(shell find ursim_core/segmentation/maoris ursim_core/matching/csrc -name '*.py' -o -name '*.c' -o -name '*.h') ursim_core/native.py ursim_core/matching/kernels.py | $(VENV)/.installed-core
	@echo "Compiling the segmentation and matching kernels (once; a few seconds)..."
	$(BIN)/python -c "from ursim_core.segmentation.maoris import compile_kernels; print(f'{compile_kernels():.1f} s')"
	$(BIN)/python -c "from ursim_core.matching.kernels import build; print(build())"
	touch $@

# The sources byte-compiled: where PYTHONDONTWRITEBYTECODE is set (many container images, this
# project's own machines) Python would compile every module again in each process it starts,
# 0.05-0.15 s of each `ursim match` (round 58). compileall rewrites only what changed.
$(VENV)/.bytecode: $(shell find ursim_core ursim_gui -name '*.py') | $(BIN)/python
	$(BIN)/python -m compileall -q ursim_core ursim_gui > /dev/null
	touch $@

run: $(VENV)/.installed-gui $(VENV)/.kernels $(VENV)/.bytecode
	$(BIN)/ursim-gui $(ARGS)

# Lint, format and the import contracts of pyproject.toml first: they take seconds and say most.
lint: $(VENV)/.installed-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/lint-imports

test: lint $(VENV)/.kernels $(VENV)/.bytecode
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m pytest -n 2 -q

bench: $(VENV)/.installed-dev $(VENV)/.kernels $(VENV)/.bytecode
	$(BIN)/ursim bench all

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
