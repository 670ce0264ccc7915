# Two commands on a fresh machine: `make demo` and `make test`; each sets up .venv itself.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test lint baselines wheel system-deps clean

# warmup compiles every env's and reference's kernels into numba's cache first, two processes at a time
demo: $(VENV)/.learn-installed
	$(BIN)/redundancy-gym warmup --workers 2 --no-progress
	$(BIN)/redundancy-gym demo --out results

# warmup first, as in demo: the tests then load the kernels the warm-up compiled (and the shipped models' rows,
# checked to 1e-3 of their returns, hold for kernels compiled in another process history)
test: $(VENV)/.test-installed
	$(BIN)/redundancy-gym warmup --workers 2 --no-progress
	$(BIN)/python -m pytest -q

# the linter, the formatter's check and the type checker, as CI runs them before the tests (configured in pyproject.toml)
lint: $(VENV)/.test-installed
	$(BIN)/ruff check redundancy_gym tests
	$(BIN)/ruff format --check redundancy_gym tests
	$(BIN)/mypy

# the learned baselines of baselines/*.yaml: trains each (seeded, CPU; TensorBoard logs in runs/baselines_tb,
# checkpoints in runs/baselines) into baselines/models/ with its training record, then evaluates every analytic
# reference and learned model on held-out seeds 20000-20019 into baselines/results/learned.{json,md,*.png}; then
# the learning curves (bench curves, resumable: run it again to go on) into baselines/results/curves.{json,md,*.png};
# their committed points are complete at the study's budgets, so on a clone it only writes the tables and plots
# again (delete baselines/results/curves/*-s?.json to train all 78 runs afresh: about 69 CPU-hours)
# (the baselines: about 60 CPU-min of training and 5 min of evaluation here, 2 cores)
baselines: $(VENV)/.test-installed
	$(BIN)/redundancy-gym baselines
	$(BIN)/redundancy-gym bench learned --json baselines/results/learned.json --no-progress
	$(BIN)/redundancy-gym bench curves --workers 2 --json baselines/results/curves.json --no-progress

# a wheel for pip-install users in dist/, carrying the kernels compiled ahead for the x86-64-v3 CPU (about two minutes
# in one process): a new process copies them into its numba cache instead of compiling; build/ goes first, as it
# would carry files of an earlier pack into the wheel
# (docs/architecture.md#kernels-shipped-in-the-wheel)
wheel: $(VENV)/.test-installed
	$(BIN)/redundancy-gym warmup --pack --no-progress
	rm -rf build
	$(BIN)/pip wheel -q --no-deps --no-build-isolation -w dist .

# libosmesa6 renders headless (import redundancy_gym selects MUJOCO_GL=osmesa without a display); installed when
# missing and run as root
system-deps:
	@if ! ldconfig -p 2>/dev/null | grep -q libOSMesa; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing libosmesa6"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libosmesa6 >/dev/null; \
	  else \
	    echo "warning: libosmesa6 is missing; headless rendering needs 'sudo apt-get install libosmesa6'"; \
	  fi; \
	fi

# the learn extra brings torch with its CUDA wheels: about 7 GB installed, and as much again while pip unpacks them;
# no pip cache (it would keep a third copy), and a clear message when the disk is short instead of pip's OSError
$(VENV)/bin/python:
	@free=$$(df -Pk . | awk 'NR==2 {print int($$4 / 1048576)}'); \
	if [ "$$free" -lt 12 ]; then echo "warning: $$free GiB free here; installing the test and learn extras needs about 12 GiB"; fi
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --no-cache-dir --upgrade pip

# the demo evaluates the shipped learned baselines (stable-baselines3 .zip files) and writes Minari datasets: core +
# the learn and dataset extras
$(VENV)/.learn-installed: pyproject.toml | $(VENV)/bin/python system-deps
	$(BIN)/pip install -q --no-cache-dir -e ".[learn,dataset]"
	touch $@

$(VENV)/.test-installed: pyproject.toml | $(VENV)/bin/python system-deps
	$(BIN)/pip install -q --no-cache-dir -e ".[test]"
	touch $@ $(VENV)/.learn-installed

# numba's on-disk cache keys a kernel on its own file only: after editing a kernel that others call, clean
clean:
	rm -rf $(VENV) results runs .pytest_cache .mypy_cache .ruff_cache build dist redundancy_gym/packed_kernels
	find redundancy_gym -name '*.nbi' -delete -o -name '*.nbc' -delete
