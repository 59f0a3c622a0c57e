# Two commands for a fresh machine: `make run` and `make test`. Each creates .venv and installs
# what it needs by itself (nothing is assumed to be installed by hand).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.faultmas-installed
PURE_PYTHON := FAULTMAS_PURE_PYTHON=1

CHROMIUM := /usr/bin/chromium

.PHONY: run test test-slow test-install bench install speedups browser clean jason-tests campaign soak eval-teams

# constraints.txt: the exact versions (pyproject.toml publishes ranges; issue 23). Installs go through it.
# Each step says what it does in one line (the commands and pip's progress stay out of the way; errors still show).
$(STAMP): pyproject.toml constraints.txt Makefile setup.py
	@echo "faultmas: creating the virtual environment $(VENV)"
	@$(PYTHON) -m venv $(VENV)
	@$(PY) -m pip install -q --upgrade pip
	@echo "faultmas: installing faultmas and its dependencies at the versions of constraints.txt, with ROS 2 Jazzy wheels and the test tools (a few minutes the first time)"
	@# The ROS 2 wheels first: they bring lark-parser 0.12, which overwrites Lark 1.x ...
	@# (not compiled here: `speedups` compiles the interpreter in place, once)
	@# editable_mode=compat: the editable install is a plain path entry (this folder) in a .pth; setuptools'
	@# default, an import hook module, imports pathlib, re, enum... at every interpreter start of the venv:
	@# 2/3 of `python -c pass`, which a user's `pip install faultmas` never pays (issue 23, start-up).
	@$(PURE_PYTHON) $(PY) -m pip install -q -c constraints.txt -e '.[ros2,dev]' --config-settings editable_mode=compat
	@echo "faultmas: putting Lark 1.x back over the lark-parser 0.12 the ROS 2 wheels bring"
	@# ... so Lark 1.x is reinstalled last (see ../shared/notes/ros2-and-zenoh.md, 1.4).
	@$(PY) -m pip install -q --force-reinstall --no-deps 'lark==1.3.1'
	@$(PY) -c 'import lark, sys; sys.exit(0 if lark.__version__.startswith("1.") else "lark-parser 0.12 shadows Lark 1.x")'
	@touch $(STAMP)
	@echo "faultmas: installed into $(VENV)"

install: $(STAMP)

# The compiled interpreter (agentspeak/_speedups.py) and the camera's z-buffer loop (robot_bridge/sim/zbuffer.py),
# rebuilt in place for sources edited since the last build; a no-op when nothing changed. Without it an edited
# module runs from source (the camera draws with numpy), with a warning.
speedups: $(STAMP)
	@$(PY) setup.py -q build_ext --inplace

run: speedups
	$(VENV)/bin/faultmas run

# The inspector's browser tests drive Debian's Chromium with Playwright (Playwright's own browser download
# cannot work here: see ../shared/notes/browser-tests.md). Installed once, as root (CI runs as root).
browser: $(CHROMIUM)
$(CHROMIUM):
	command -v apt-get >/dev/null && [ "$$(id -u)" = 0 ] || { echo "install Debian's chromium (apt-get install chromium) for the browser tests" >&2; exit 1; }
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null

# On TEST_WORKERS pytest-xdist workers: much of the suite waits (processes starting, ROS discovery, the network,
# agents' deadlines), so two workers overlap those waits on 2 cores. --dist loadfile keeps each test file on one
# worker (a module fixture that starts a team starts once). TEST_WORKERS=0: one process, as plain pytest.
TEST_WORKERS ?= 2
XDIST = -n $(TEST_WORKERS) --dist loadfile
test: speedups browser
	$(PY) -m pytest -q -p no:cacheprovider -m "not slow" $(XDIST)
	# the language suite again on the interpreter run from source (what runs without a C compiler)
	$(PURE_PYTHON) $(PY) -m pytest -q -p no:cacheprovider $(XDIST) tests/agentspeak

# The end-to-end tests marked `slow` (minutes each, each covered in shorter form by `make test`), kept out of
# `make test`'s ~10 min budget
test-slow: speedups browser
	$(PY) -m pytest -q -p no:cacheprovider -m slow

# The reliability campaign (docs/reliability.md): every input boundary fuzzed for FUZZ_MINUTES (compiled,
# tests/hardening/fuzz_campaign.py), then with FAULTMAS_FUZZ_EXAMPLES inputs each (default 20,000; `make test`
# runs 40), compiled and from source. Hours at the default.
# Then the chaos matrix (tests/hardening/test_chaos_campaign.py: SIGKILL/SIGSTOP of agents and ROS 2 nodes in
# `faultmas run`, the pair, a team of 6 and --bridge ros2; ~30 min), each case's outcome printed (CHAOS | ...),
# and the multi-host run in three network namespaces with a cut link (tests/hardening/test_multihost_netns.py, root).
FUZZ_MINUTES ?= 60
campaign: speedups
	$(PY) -m tests.hardening.fuzz_campaign --minutes $(FUZZ_MINUTES) --found fuzz-found
	FAULTMAS_FUZZ_PROFILE=campaign $(PY) -m pytest -q -p no:cacheprovider tests/hardening/test_fuzz_boundaries.py
	FAULTMAS_FUZZ_PROFILE=campaign $(PURE_PYTHON) $(PY) -m pytest -q -p no:cacheprovider tests/hardening/test_fuzz_boundaries.py
	FAULTMAS_CHAOS=campaign $(PY) -m pytest -q -s -p no:cacheprovider tests/hardening/test_chaos_campaign.py \
		tests/hardening/test_multihost_netns.py

# The soak (tests/hardening/soak.py): one team of 6 that stays up and diagnoses fault after fault until
# SOAK_SIM_SECONDS of simulated time (default 1 h) or SOAK_WALL_SECONDS of wall time; RSS slopes (this process
# and every agent, each part by part: malloc's heaps, other anonymous and file mappings, huge pages, glibc's in-use
# and freed-but-kept bytes), threads, descriptors, Zenoh declarations, stuck intentions, per task. Each task's robot poses are
# in its row and the agents' lines in soak-agents.log (with the paths of a task that did not end correct), so a
# task can be replayed: python -m tests.hardening.soak_replay soak.jsonl N
SOAK_SIM_SECONDS ?= 3600
SOAK_WALL_SECONDS ?= 36000
soak: speedups
	$(PY) -m tests.hardening.soak --sim-seconds $(SOAK_SIM_SECONDS) --wall-seconds $(SOAK_WALL_SECONDS) --out soak.jsonl \
		--agent-log soak-agents.log

# Jason 3.3.2's own AgentSpeak unit tests, run unchanged from ../shared (see tests/jason_suite), in one
# process and with --processes (both run; fails unless each run is complete and passed: exit 0, the manager's
# PASSED, >= 468 executed, every tester heard from; else it names what is missing); prints executed/passed
JASON_TESTS ?= ../shared/jason-unit-tests
jason-tests: speedups
	@$(PY) -m tests.jason_suite $(abspath $(JASON_TESTS)); in_process=$$?; \
	$(PY) -m tests.jason_suite $(abspath $(JASON_TESTS)) --processes; processes=$$?; \
	exit $$((in_process | processes))

# A user's install, slow (~2 min: a fresh venv, plain `pip install '.[ros2]'`, then `faultmas run`), so not
# part of `make test`: tests/test_install.py (issue 23).
test-install: $(STAMP)
	FAULTMAS_INSTALL_TEST=1 $(PY) -m pytest -q -p no:cacheprovider tests/test_install.py

bench: speedups
	$(PY) -m benchmarks

# Issue 23: cooperative diagnosis in teams (docs/cooperative.md, "Teams"): TEAM_RUNS random team placements
# over the whole arena per size, N//4 faulty robots with random faults; fails unless every run is correct.
# Minutes per run for the larger teams on 2 cores (every camera costs the simulator).
TEAM_SIZES ?= 2,4,6,8,12
TEAM_RUNS ?= 10
TEAM_SEED ?= 1
eval-teams: speedups
	$(VENV)/bin/faultmas eval --faults '' --teams $(TEAM_SIZES) --runs $(TEAM_RUNS) --seed $(TEAM_SEED) --jobs 2

clean:
	rm -rf $(VENV) build *.egg-info agentspeak/_speedups.json
	find agentspeak robot_bridge -name "*.so" -delete
	rm -f robot_bridge/sim/_zbuffer.json
