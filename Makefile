# Entry point for every build and check: `make demo` and `make test` set everything up from a clean clone.
SHELL := /bin/bash
.DEFAULT_GOAL := help

PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
BUILD := build
# Root installs directly; anyone else needs sudo for the Debian packages.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

# Debian packages the offline firmware build, the emulator and the C++ checks need.
SYSTEM_PACKAGES := gcc-avr avr-libc binutils-avr arduino-core-avr avrdude simavr libsimavr-dev libelf-dev clang-format pkg-config g++ doctest-dev

.PHONY: help demo test system-deps venv generate check-generated native native-asan cpp-test \
        firmware firmware-faults harness lint format pytest bench clean

help:
	@echo "make demo      set everything up and run a virtual swarm at a lamp in the console"
	@echo "make test      set everything up and run every check (lint, C++ tests, pytest, simavr)"
	@echo "make firmware  build build/firmware/particle.elf and .hex with Debian's avr-gcc"
	@echo "make bench     run the benchmarks whose figures README reports"

# ---- setup ------------------------------------------------------------------------------------

$(BUILD)/.system-deps:
	@missing=$$(for p in $(SYSTEM_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "Installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi
	@mkdir -p $(BUILD) && touch $@

system-deps: $(BUILD)/.system-deps

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade pip
	$(VPY) -m pip install -q -e '.[dev]'
	@touch $@

venv: $(VENV)/.installed

# ---- protocol: shared/protocol.toml -> C++ header and Python module ----------------------------

GENERATED := firmware/lib/protocol/protocol_gen.h host/particlebot/protocol/generated.py

generate: $(VENV)/.installed
	$(VPY) tools/gen_protocol.py

# Fails when the committed generated files differ from what the definition gives.
check-generated: $(VENV)/.installed
	$(VPY) tools/gen_protocol.py --check

# ---- firmware logic, built for the PC ---------------------------------------------------------

LOGIC_SOURCES := $(wildcard firmware/lib/*/*.cpp)
LOGIC_HEADERS := $(wildcard firmware/lib/*/*.h)
LOGIC_INCLUDES := $(addprefix -I,$(wildcard firmware/lib/*))
NATIVE_CXX := g++
NATIVE_FLAGS := -std=gnu++11 -Wall -Wextra -Werror -Wshadow -fPIC $(LOGIC_INCLUDES)
SANITIZE := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# doctest comes from Debian's doctest-dev here and from PlatformIO's registry under `pio test -e native`.
CPP_TEST_SOURCES := $(wildcard firmware/test/*/*.cpp)

# Release build the host's virtual particles load.
$(BUILD)/native/libparticle.so: $(LOGIC_SOURCES) $(LOGIC_HEADERS)
	@mkdir -p $(@D)
	$(NATIVE_CXX) $(NATIVE_FLAGS) -O2 -shared -o $@ $(LOGIC_SOURCES)

# Sanitized build the firmware-logic tests load (pytest preloads libasan for it).
$(BUILD)/native-asan/libparticle.so: $(LOGIC_SOURCES) $(LOGIC_HEADERS)
	@mkdir -p $(@D)
	$(NATIVE_CXX) $(NATIVE_FLAGS) $(SANITIZE) -O1 -g -shared -o $@ $(LOGIC_SOURCES)

$(BUILD)/native-asan/firmware_tests: $(LOGIC_SOURCES) $(LOGIC_HEADERS) $(CPP_TEST_SOURCES)
	@mkdir -p $(@D)
	$(NATIVE_CXX) $(NATIVE_FLAGS) $(SANITIZE) -O1 -g -I/usr/include/doctest -o $@ $(CPP_TEST_SOURCES) $(LOGIC_SOURCES)

native: $(BUILD)/native/libparticle.so
native-asan: $(BUILD)/native-asan/libparticle.so $(BUILD)/native-asan/firmware_tests

# The C++ unit tests of the logic, reading the golden frames in shared/vectors.toml.
cpp-test: $(BUILD)/native-asan/firmware_tests
	$(BUILD)/native-asan/firmware_tests shared/vectors.toml

# ---- firmware for the particle (ATmega32U4, Debian's avr-gcc and Arduino core) ----------------
# (filled in by the firmware build: see firmware/README section in README.md)

firmware: $(BUILD)/.system-deps

# ---- firmware in the loop: simavr harness ------------------------------------------------------

harness: $(BUILD)/.system-deps

# ---- checks -------------------------------------------------------------------------------------

lint: $(VENV)/.installed $(BUILD)/.system-deps
	$(VENV)/bin/ruff check host tests tools
	$(VENV)/bin/ruff format --check host tests tools
	$(VENV)/bin/mypy
	clang-format --dry-run --Werror $$(git ls-files 'firmware/*.cpp' 'firmware/*.h' 'tools/*.c')

format: $(VENV)/.installed
	$(VENV)/bin/ruff format host tests tools
	$(VENV)/bin/ruff check --fix host tests tools
	clang-format -i $$(git ls-files 'firmware/*.cpp' 'firmware/*.h' 'tools/*.c')

ASAN_RUNTIME = $(shell $(NATIVE_CXX) -print-file-name=libasan.so)

# Firmware-logic tests run against the sanitized library; everything else against the release one.
pytest: $(VENV)/.installed native native-asan firmware harness
	LD_PRELOAD=$(ASAN_RUNTIME) ASAN_OPTIONS=detect_leaks=0 \
	  PARTICLEBOT_NATIVE_LIB=$(BUILD)/native-asan/libparticle.so \
	  $(VENV)/bin/pytest -q tests/firmware
	$(VENV)/bin/pytest -q --ignore=tests/firmware tests

test: system-deps venv check-generated lint cpp-test pytest

demo: system-deps venv native
	$(VENV)/bin/particlebot demo

bench: venv native firmware harness
	$(VPY) tools/bench.py

clean:
	rm -rf $(BUILD)
