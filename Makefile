# The two commands a newcomer needs: `make run` and `make test`.
# The first interpreter that runs and is 3.11+ (pyenv shims may exist but not run).
PYTHON ?= $(shell for p in python3 python3.11 python3.12 python3.13; do $$p -c 'import sys; assert sys.version_info >= (3, 11)' 2>/dev/null && { echo $$p; break; }; done)
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(VENV)/bin/pip
STAMP  := $(VENV)/.install-stamp
ROS_DEPS := ros-jazzy-rclpy ros-jazzy-rmw-fastrtps-cpp ros-jazzy-common-interfaces
export RMW_IMPLEMENTATION ?= rmw_fastrtps_cpp
# Keep test and demo traffic on this machine.
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST

.PHONY: install run test bench bench-quick compare-extras clean

install: $(STAMP)

$(STAMP): setup.py package.xml
	@test -n "$(PYTHON)" || { echo "Python 3.11 or newer is required (none found on PATH)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	$(PIP) install -q $(ROS_DEPS)
	$(PIP) install -q -e '.[test,bench,render,foxglove]'
	$(PY) -m physics_core.warm_up
	touch $(STAMP)

run: install
	$(VENV)/bin/physics-node --record recordings/session-$$(date +%Y%m%d-%H%M%S).mcap $(ARGS)

test: install
	$(PY) -m pytest -q tests $(PYTEST_ARGS)

bench: install
	$(VENV)/bin/physics-bench all

bench-quick: install
	$(VENV)/bin/physics-bench all --quick

compare-extras: install
	$(PIP) install -q -e '.[compare]'

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
