# The one entry point. `make run` and `make test` install what is missing
# (Debian packages, as root), build, then do their job.
#
#   make run        main demo: ice patches with slip recovery on, then off
#   make test       every test: unit, physics, closed-loop scenarios, firmware
#   make firmware   cross-compile the board images (mps2-an500, stm32h743)
#   make bench      Google Benchmark of the controller (host)
#   make plots RUN=out/<name>   figures from a run's log.csv
#   make sweep SWEEP=sim_host/sweeps/<name>.yaml   a sweep on this machine
#   make golden     rewrite the golden replay's reference (an intended change)
#   make web        the 3D replay page's template (npm + esbuild, into $(BUILD)/web)
#   make replay-figure  the replay screenshots of docs/replay.md

SHELL := /bin/bash
BUILD ?= build/host
JOBS ?= $(shell nproc)

HOST_PKGS := build-essential cmake pkg-config libode-dev libmujoco-dev libeigen3-dev \
             libyaml-cpp-dev googletest libgtest-dev libbenchmark-dev \
             python3 python3-matplotlib python3-numpy python3-yaml parallel
# The tests' own: a single-node Slurm cluster (tests/sweep/slurm_local.sh).
TEST_PKGS := slurm-wlm munge
# The replay page (web/replay/) and its browser test (tests/browser/).
WEB_PKGS  := nodejs npm
BROWSER_PKGS := chromium
FW_PKGS   := gcc-arm-none-eabi libnewlib-arm-none-eabi \
             libstdc++-arm-none-eabi-newlib qemu-system-arm \
             clang libclang-rt-14-dev

.PHONY: all deps deps-host deps-fw deps-test deps-web deps-web-apt deps-browser host web browser-test-deps \
        replay-figure run test firmware bench plots sweep golden clean

all: host

# Install only what dpkg does not already have.
define install_missing
	@missing=""; for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  if [ "$$(id -u)" != 0 ]; then echo "need root to install:$$missing" >&2; exit 1; fi; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null; \
	fi
endef

deps-host:
	$(call install_missing,$(HOST_PKGS))

deps-fw:
	$(call install_missing,$(FW_PKGS))

deps-test:
	$(call install_missing,$(TEST_PKGS))

# node and npm: Debian's packages unless the machine has both already
# (some node builds ship their own npm, which Debian's npm cannot sit beside).
deps-web:
	@command -v node >/dev/null && command -v npm >/dev/null || $(MAKE) --no-print-directory deps-web-apt

deps-web-apt:
	$(call install_missing,$(WEB_PKGS))

deps-browser:
	$(call install_missing,$(BROWSER_PKGS))

deps: deps-host deps-fw deps-test deps-web deps-browser

$(BUILD)/CMakeCache.txt: | deps-host
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

host: deps-host $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j$(JOBS)

# replay.html's page template: three.js bundled by esbuild (both from npm, at
# the versions of web/replay/package-lock.json) into one script inlined in
# web/replay/template.html. node_modules stays in $(BUILD)/web.
WEB := $(BUILD)/web
WEB_SRC := $(wildcard web/replay/src/*.js) web/replay/template.html web/replay/inline.mjs

$(WEB)/node_modules/.package-lock.json: web/replay/package.json web/replay/package-lock.json | deps-web
	@mkdir -p $(WEB)
	cp web/replay/package.json web/replay/package-lock.json $(WEB)/
	cd $(WEB) && npm ci --no-audit --no-fund --loglevel=error

$(WEB)/replay_template.html: $(WEB)/node_modules/.package-lock.json $(WEB_SRC)
	NODE_PATH=$(abspath $(WEB))/node_modules $(WEB)/node_modules/.bin/esbuild web/replay/src/main.js \
	  --bundle --minify --format=iife --target=es2020 --log-level=warning --outfile=$(WEB)/replay.js
	node web/replay/inline.mjs web/replay/template.html $(WEB)/replay.js $@

web: $(WEB)/replay_template.html

# playwright-core for tests/browser/ (it drives Debian's chromium).
BROWSER_TEST := $(BUILD)/browser-test
$(BROWSER_TEST)/node_modules/.package-lock.json: tests/browser/package.json tests/browser/package-lock.json | deps-web
	@mkdir -p $(BROWSER_TEST)
	cp tests/browser/package.json tests/browser/package-lock.json $(BROWSER_TEST)/
	cd $(BROWSER_TEST) && npm ci --no-audit --no-fund --loglevel=error

browser-test-deps: deps-browser $(BROWSER_TEST)/node_modules/.package-lock.json

# docs/replay.md's figures: the browser test's screenshots at the first slip
# of its run, at the 20th of the ice patches (a touch-down on mu 0.2), and
# at the 40th of the trot across them (a diagonal pair landing on ice).
replay-figure: host web browser-test-deps
	node tests/browser/replay_test.mjs --build $(BUILD) --screenshot docs/figures/replay_slip.png
	node tests/browser/replay_test.mjs --build $(BUILD) --scenario sim_host/scenarios/ice_patches.yaml \
	  --duration 90 --slip 20 --screenshot docs/figures/replay_ice_patches.png
	node tests/browser/replay_test.mjs --build $(BUILD) --scenario sim_host/scenarios/trot_ice_patches.yaml \
	  --duration 20 --slip 40 --screenshot docs/figures/replay_trot_ice_patches.png
	node tests/browser/replay_test.mjs --build $(BUILD) --scenario sim_host/scenarios/ice_patches_map.yaml \
	  --duration 90 --map --screenshot docs/figures/replay_friction_map.png

# The paper's ice slab, with slip recovery and without, then its figures and
# a table of the two runs beside the paper's. The build is quiet: its output
# goes to $(BUILD)/build.log, and only a failure prints it.
run: deps-host
	@mkdir -p $(BUILD) out
	@printf 'building the simulator and the controller (log: %s) ... ' $(BUILD)/build.log
	@if $(MAKE) --no-print-directory host > $(BUILD)/build.log 2>&1; then echo done; \
	 else echo FAILED; grep -E -A3 'error|Error' $(BUILD)/build.log | head -60; exit 1; fi
	@# The replay page needs npm's packages (the first time, the network): without
	@# it the runs go on with no replay.
	@printf 'building the replay page (log: %s) ... ' $(BUILD)/web.log
	@if $(MAKE) --no-print-directory web > $(BUILD)/web.log 2>&1; then echo done; \
	 else echo "FAILED: the runs write no replay.html (see the log)"; fi
	@replay=$$(test -f $(WEB)/replay_template.html && echo --replay); \
	 $(BUILD)/hyq_sim run sim_host/scenarios/ice_patches.yaml --recovery on $$replay --out out/ice_patches_on && \
	 $(BUILD)/hyq_sim run sim_host/scenarios/ice_patches.yaml --recovery off $$replay --out out/ice_patches_off
	@printf 'drawing the figures (log: out/plots.log) ... '
	@if python3 docs/plots.py out/ice_patches_on --compare out/ice_patches_off > out/plots.log 2>&1; then echo done; \
	 else echo FAILED; cat out/plots.log; exit 1; fi
	@python3 docs/run_report.py out/ice_patches_on out/ice_patches_off

test: deps firmware host web browser-test-deps
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# Board images into build/fw-<board>/ (ELF, .bin, .map). The build fails if
# an image links heap or unwinding symbols (firmware/cross/check_image.sh).
# The skeleton port is compiled, not linked, so its interface stays complete.
FW_BOARDS := mps2-an500 stm32h743
firmware: deps-fw
	@set -e; for b in $(FW_BOARDS) skeleton; do \
	  cmake -S firmware/cross -B build/fw-$$b -DHYQ_BOARD=$$b -DCMAKE_BUILD_TYPE=Release \
	    -DCMAKE_TOOLCHAIN_FILE=$(CURDIR)/firmware/cross/arm-none-eabi.cmake >/dev/null; \
	  cmake --build build/fw-$$b -j$(JOBS); \
	done; \
	for b in $(FW_BOARDS); do arm-none-eabi-size -A build/fw-$$b/hyq_*.elf | awk -v b=$$b \
	  '$$1 ~ /^\.(vectors|text|rodata|init_array|data)$$/ { f += $$2 } $$1 ~ /^\.(data|bss|fast_bss|stack|noinit)$$/ { r += $$2 } \
	   END { printf "%-11s flash %7d bytes   RAM %7d bytes\n", b, f, r }'; done

bench: host
	$(BUILD)/hyq_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

# The board's per-stage instruction counts over whole scenario traces (QEMU
# -icount), against their budgets; then docs/performance.md's table.
timing: firmware host
	cd $(BUILD) && ctest --output-on-failure -L timing -j$(JOBS)
	python3 docs/performance.py $(BUILD)

plots:
	@test -n "$(RUN)" || { echo "usage: make plots RUN=out/<name>"; exit 2; }
	python3 docs/plots.py $(RUN)

# A scenario over seeds and parameters, its cases run by GNU parallel, then
# out/sweeps/<name>/sweep.json, sweep.csv and plots (docs/sweeps.md).
sweep: host
	@test -n "$(SWEEP)" || { echo "usage: make sweep SWEEP=sim_host/sweeps/<name>.yaml"; exit 2; }
	$(BUILD)/hyq_sim sweep $(SWEEP) --jobs $(JOBS)

# docs/results.md from the scenarios over seeds 1-32, recovery on and off,
# plus the slip scenarios on MuJoCo and ice_patches/ramp over a range of
# contact stiffness (seeds 1-8), all run again with the current build (into
# out/results/; without --fresh docs/results.py resumes, keeping the cases
# already there).
.PHONY: results timing real-plant terrain-sets
results: host
	python3 docs/results.py --fresh --jobs $(JOBS)

# docs/results.md's real-plant section: the scenarios on the ideal and the
# hyq plant (ODE seeds 1-8, MuJoCo 1-4) and the margin map (torque-loop
# bandwidth x delay, trunk mass x inertia; docs/figures/margin_*.png), into
# out/real_plant/.
real-plant: host
	python3 docs/real_plant.py --run --fresh --jobs $(JOBS)

# docs/results.md's drawn-terrain section: the validation and test sets
# (sim_host/sweeps/terrain_*.yaml), into out/real_plant/.
terrain-sets: host
	python3 docs/real_plant.py --terrain --fresh --jobs $(JOBS)

# The golden replays' references, after a change whose new behaviour is
# intended (say why in the commit). `hyq_golden record` also re-records the
# input traces from the simulator.
golden: host
	$(BUILD)/hyq_golden reference

clean:
	rm -rf build
