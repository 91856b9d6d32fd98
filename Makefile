# copi: `make run` reproduces, `make test` checks, `make bench` measures.
# Each target creates .venv and installs copi with what it needs on first use; later runs
# reuse it (the install is redone only when pyproject.toml changes). The install ends by
# compiling copi's numba kernels once (about 30 s), and again whenever a file that holds
# kernels changes, so that no later command waits for them.

PYTHON ?= $(shell command -v python3.11 2>/dev/null || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.install-stamp
KERNELS := $(VENV)/.kernels-stamp
# Every source file that holds numba kernels: copi stamps their on-disk cache with all of
# them (copi._kernel_cache), so a change to any one recompiles them all; it is done here,
# once, not inside the first command or test that needs them.
KERNEL_SOURCES := $(shell grep -rl njit src/copi --include='*.py' 2>/dev/null)
RESULTS ?= results

.PHONY: install run test lint typecheck pytest docs bench clean shell

install: $(KERNELS)

$(STAMP): pyproject.toml
	@test -n "$(PYTHON)" || { echo "make: need Python >= 3.11 (python3.11 or python3)"; exit 2; }
	$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
		{ echo "make: need Python >= 3.11, found $$($(PYTHON) --version)"; exit 2; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/python -m pip install --quiet -e '.[dev,peers]' || \
		echo "make: navground could not be installed: the benchmark leaves its peers out"
	($(BIN)/python tools/cpu_torch.py && \
		$(BIN)/python -m pip install --quiet 'torch==2.13.0' && \
		$(BIN)/python -m pip install --quiet -e '.[dev,peers,rl]') || \
		echo "make: no CPU build of torch here: RL training (copi rl train) is left out"
	touch $(STAMP)

$(KERNELS): $(STAMP) $(KERNEL_SOURCES)
	$(BIN)/python -m copi._warmup
	touch $(KERNELS)

# The paper's Experiment 1 end to end (learn, 1549 dynamic worlds in two modes, report),
# then the figures of the capabilities and a few worlds with an animation.
run: install
	$(BIN)/copi reproduce -o $(RESULTS)
	$(BIN)/copi figures $(RESULTS)/capabilities-faithful.npz -o $(RESULTS)/figures
	$(BIN)/copi world sample --seed 0 -n 4 -o $(RESULTS)/worlds/worlds.json
	$(BIN)/copi world show $(RESULTS)/worlds/worlds.json -o $(RESULTS)/worlds --gif

lint: install
	$(BIN)/ruff check src tests benchmarks studies tools

typecheck: install
	$(BIN)/mypy

# two processes: the tests are independent (each writes only below its tmp_path)
pytest: install
	$(BIN)/pytest -n 2

test: lint typecheck pytest docs

# The documentation site into site/, warnings as errors (a broken link fails it).
docs: install
	$(BIN)/python -m pip install --quiet -e '.[docs]'
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet

# The reference planner is compared with extremitypathfinder when it can be installed;
# the long data checks (every Moving AI scenario line) run here, not in `make test`. The
# timings run even when a slow check fails; make bench then ends with that failure.
bench: install
	-$(BIN)/python -m pip install --quiet extremitypathfinder || echo "extremitypathfinder unavailable: no ratio"
	$(BIN)/pytest -m slow; slow=$$?; $(BIN)/python benchmarks/run.py && exit $$slow

# A shell with copi (and the project's python and pip) on the PATH; exit to leave it.
shell: install
	@echo "copi is on the PATH of this shell ($(CURDIR)/$(BIN)); exit to leave it"
	@VIRTUAL_ENV="$(CURDIR)/$(VENV)" PATH="$(CURDIR)/$(BIN):$$PATH" $${SHELL:-/bin/sh}

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache .mypy_cache .ruff_cache
