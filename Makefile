# Two commands for a fresh machine: `make run` and `make test`. Each creates .venv and installs
# what it needs by itself (nothing is assumed to be installed by hand).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.faultmas-installed
PURE_PYTHON := FAULTMAS_PURE_PYTHON=1

.PHONY: run test bench install speedups clean campaign

$(STAMP): pyproject.toml Makefile setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	# The ROS 2 wheels first: they bring lark-parser 0.12, which overwrites Lark 1.x ...
	# (not compiled here: `speedups` compiles the interpreter in place, once)
	$(PURE_PYTHON) $(PY) -m pip install -q -e '.[ros2,dev]'
	# ... so Lark 1.x is reinstalled last (see ../shared/notes/ros2-and-zenoh.md, 1.4).
	$(PY) -m pip install -q --force-reinstall --no-deps 'lark==1.3.1'
	$(PY) -c 'import lark, sys; sys.exit(0 if lark.__version__.startswith("1.") else "lark-parser 0.12 shadows Lark 1.x")'
	touch $(STAMP)

install: $(STAMP)

# The compiled interpreter (agentspeak/_speedups.py) and the camera's z-buffer loop (robot_bridge/sim/zbuffer.py),
# rebuilt in place for sources edited since the last build; a no-op when nothing changed. Without it an edited
# module runs from source (the camera draws with numpy), with a warning.
speedups: $(STAMP)
	$(PY) setup.py -q build_ext --inplace

run: speedups
	$(VENV)/bin/faultmas run

test: speedups
	$(PY) -m pytest -q -p no:cacheprovider
	# the language suite again on the interpreter run from source (what runs without a C compiler)
	$(PURE_PYTHON) $(PY) -m pytest -q -p no:cacheprovider tests/agentspeak

# The reliability campaign (docs/reliability.md): every input boundary fuzzed with FAULTMAS_FUZZ_EXAMPLES
# inputs each (default 20,000; `make test` runs 40), compiled and from source. Hours at the default.
campaign: speedups
	FAULTMAS_FUZZ_PROFILE=campaign $(PY) -m pytest -q -p no:cacheprovider tests/hardening/test_fuzz_boundaries.py
	FAULTMAS_FUZZ_PROFILE=campaign $(PURE_PYTHON) $(PY) -m pytest -q -p no:cacheprovider tests/hardening/test_fuzz_boundaries.py

bench: speedups
	$(PY) -m benchmarks

clean:
	rm -rf $(VENV) build *.egg-info agentspeak/_speedups.json
	find agentspeak robot_bridge -name "*.so" -delete
	rm -f robot_bridge/sim/_zbuffer.json
