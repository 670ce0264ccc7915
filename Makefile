# Two commands on a fresh machine: `make demo` and `make test`; each sets up .venv itself.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test baselines system-deps clean

demo: $(VENV)/.core-installed
	$(BIN)/redundancy-gym demo --out results

test: $(VENV)/.test-installed
	$(BIN)/python -m pytest -q

# the learned baselines of baselines/*.yaml: trains each (seeded, CPU; TensorBoard logs in runs/baselines_tb) into
# baselines/models/, then evaluates it on held-out seeds 20000-20019 into baselines/results/ (about 5 min here)
BASELINE_SEEDS := --episodes 20 --seed 20000 --no-progress
baselines: $(VENV)/.test-installed
	$(BIN)/redundancy-gym train redundancy_gym/PlanarReach-v0 --wrapper nullspace --algo ppo --seed 0 --no-progress \
	  --config baselines/ppo-nullspace-planar_reach.yaml --out baselines/models/ppo-nullspace-planar_reach.zip \
	  --tensorboard runs/baselines_tb
	$(BIN)/redundancy-gym train redundancy_gym/PlanarReach-v0 --algo ppo --seed 0 --no-progress \
	  --config baselines/ppo-joint-planar_reach.yaml --out baselines/models/ppo-joint-planar_reach.zip \
	  --tensorboard runs/baselines_tb
	$(BIN)/redundancy-gym train redundancy_gym/PlanarReach-v0 --algo bc --seed 0 --no-progress \
	  --config baselines/bc-joint-planar_reach.yaml --out baselines/models/bc-joint-planar_reach.zip
	$(BIN)/redundancy-gym eval redundancy_gym/PlanarReach-Nullspace-v0 --policy ppo-nullspace $(BASELINE_SEEDS) \
	  --json baselines/results/ppo-nullspace-planar_reach.json
	$(BIN)/redundancy-gym eval redundancy_gym/PlanarReach-v0 --policy ppo-joint $(BASELINE_SEEDS) \
	  --json baselines/results/ppo-joint-planar_reach.json
	$(BIN)/redundancy-gym eval redundancy_gym/PlanarReach-v0 --policy bc-joint $(BASELINE_SEEDS) \
	  --json baselines/results/bc-joint-planar_reach.json
	$(BIN)/redundancy-gym eval redundancy_gym/PlanarReach-v0 --policy clik $(BASELINE_SEEDS) \
	  --json baselines/results/clik-planar_reach.json

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

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip

$(VENV)/.core-installed: pyproject.toml | $(VENV)/bin/python system-deps
	$(BIN)/pip install -q -e .
	touch $@

$(VENV)/.test-installed: pyproject.toml | $(VENV)/bin/python system-deps
	$(BIN)/pip install -q -e ".[test]"
	touch $@ $(VENV)/.core-installed

# numba's on-disk cache keys a kernel on its own file only: after editing a kernel that others call, clean
clean:
	rm -rf $(VENV) results runs .pytest_cache
	find redundancy_gym -name '*.nbi' -delete -o -name '*.nbc' -delete
