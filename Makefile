# matrix-tracker: the two commands that matter are `make demo` and `make test` (see README.md).
SHELL := /bin/bash
.DEFAULT_GOAL := help
IN_ENV := source scripts/env.sh &&
# Where the experiments write their report (its PNGs go to images/results/ beside it); CI writes elsewhere.
RESULTS ?= docs/RESULTS.md

.PHONY: help setup build data test test-fast demo bench clean experiments experiments-quick experiments-standard

help:
	@echo "make setup  - create .venv (pinned), colcon build ros2_ws, install offline weights (idempotent)"
	@echo "make test   - run every test (unit, integration, ROS 2 over DDS, system)"
	@echo "make test-fast - every test but the DDS (ros), system and slow ones (under 3 minutes)"
	@echo "make data   - check ../shared (MATRIX_SHARED), else fetch the public MATRIX sample, else say what to put where"
	@echo "make demo   - replay the real MATRIX sample through ROS 2 and write pictures to out/demo"
	@echo "make bench  - the speed figures of every component (scripts/bench_*.py but the soak) -> docs/benchmarks.md"
	@echo "make build  - colcon build only"
	@echo "make experiments       - the paper's experiments at full size (hours) -> \$$RESULTS (docs/RESULTS.md) + PNGs"
	@echo "make experiments-standard - the size of docs/RESULTS.md (about 2.5 h, two steps at once) -> \$$RESULTS + docs/results/standard/"
	@echo "make experiments-quick - the same as a smoke test (a few minutes; numbers meaningless), e.g. RESULTS=out/quick/RESULTS.md"

setup:
	bash scripts/setup.sh

build:
	bash scripts/build.sh

data:
	bash scripts/data.sh

# test and demo fail early, before setup, when their data is missing (the message of `make data`).
test:
	bash scripts/data.sh --require matrix_sample,multiviewx_sample
	$(MAKE) setup
	$(IN_ENV) python -m pytest

# No setup: for the edit-test loop of a machine already set up (system tests are all marked ros and slow).
test-fast:
	$(IN_ENV) python -m pytest -m "not ros and not slow"

demo:
	bash scripts/data.sh --require matrix_sample
	$(MAKE) setup
	$(IN_ENV) bash scripts/demo.sh

# The soak (45 min) runs alone: python scripts/bench_soak.py
bench: setup
	$(IN_ENV) python scripts/run_benchmarks.py

experiments: setup
	$(IN_ENV) matrix-tracker experiments --mode full --out out/experiments --report $(RESULTS)

experiments-standard: setup
	$(IN_ENV) matrix-tracker experiments --mode standard --jobs 2 --out out/experiments --report $(RESULTS)

experiments-quick: setup
	$(IN_ENV) matrix-tracker experiments --mode quick --out out/experiments --report $(RESULTS)

clean:
	rm -rf ros2_ws/build ros2_ws/install ros2_ws/log ros2_ws/cli_overlay ros2_ws/interfaces_overlay out .pytest_cache
