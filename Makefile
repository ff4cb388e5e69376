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
# clang brings libFuzzer (Debian's libclang-rt-*-dev) for the frame parser's fuzz target.
SYSTEM_PACKAGES := gcc-avr avr-libc binutils-avr arduino-core-avr avrdude simavr libsimavr-dev libelf-dev clang-format pkg-config g++ doctest-dev clang

.PHONY: help demo test system-deps venv generate check-generated native native-asan cpp-test \
        fuzz firmware firmware-faults harness lint format pytest check bench docs docs-check clean

help:
	@echo "make demo      set everything up and run a virtual swarm at a lamp in the console"
	@echo "make test      set everything up and run every check (lint, C++ tests, pytest, simavr)"
	@echo "make check     the fast tier for the edit-test loop: C++ tests and pytest without the"
	@echo "               simavr, dask, e2e and slow tiers (under 3 minutes)"
	@echo "make firmware  build build/firmware/particle.elf and .hex with Debian's avr-gcc"
	@echo "make bench     run the benchmarks in benchmarks/ whose figures the performance page reports"
	@echo "make docs      build the documentation site into build/site (open build/site/index.html)"

# ---- setup ------------------------------------------------------------------------------------

# The stamp is an included makefile: when make has to create it (installing the packages), it
# then reads this Makefile again, so the wildcards below (the Arduino core's sources) see the
# files the packages just installed. Goals that need no package (help, clean) skip it.
# It depends on the Makefile, so that a package added to SYSTEM_PACKAGES is installed on a machine
# that was set up before (checking the list again takes a fraction of a second).
$(BUILD)/.system-deps: Makefile
	@missing=$$(for p in $(SYSTEM_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "Installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi
	@mkdir -p $(BUILD) && echo '# Debian packages checked by make' > $@

ifneq ($(filter-out help clean,$(or $(MAKECMDGOALS),$(.DEFAULT_GOAL))),)
include $(BUILD)/.system-deps
endif

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

# ---- coverage-guided fuzzing of the receive path (libFuzzer, as nanopb does) --------------------
# firmware/fuzz/corpus is committed (the golden frames and bad streams of shared/vectors.toml);
# what a run discovers goes to build/fuzz/corpus, and a crash leaves its input in build/fuzz/.

FUZZ_CXX := clang++
FUZZ := $(BUILD)/fuzz
FUZZ_SECONDS ?= 10
FUZZ_SOURCES := $(filter-out firmware/lib/capi/%,$(LOGIC_SOURCES))

$(FUZZ)/frame_parser_fuzz: firmware/fuzz/frame_parser_fuzz.cpp $(FUZZ_SOURCES) $(LOGIC_HEADERS) \
    | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(FUZZ_CXX) -std=gnu++11 -Wall -Wextra -Werror -g -O1 \
	  -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all $(LOGIC_INCLUDES) \
	  -o $@ $< $(FUZZ_SOURCES)

# A bounded run: FUZZ_SECONDS of new inputs after replaying the corpus.
fuzz: $(FUZZ)/frame_parser_fuzz
	@mkdir -p $(FUZZ)/corpus
	$(FUZZ)/frame_parser_fuzz -max_total_time=$(FUZZ_SECONDS) -max_len=4096 -print_final_stats=1 \
	  -artifact_prefix=$(FUZZ)/ $(FUZZ)/corpus firmware/fuzz/corpus

# ---- firmware for the particle (ATmega32U4, Debian's avr-gcc and Arduino core) ----------------
# PlatformIO (platformio.ini) needs its own downloads; this build needs only Debian packages.

AVR_CC := avr-gcc
AVR_CXX := avr-g++
AVR_AR := avr-gcc-ar
AVR_OBJCOPY := avr-objcopy
AVR_SIZE := avr-size
ARDUINO_AVR := /usr/share/arduino/hardware/arduino/avr
ARDUINO_CORE := $(ARDUINO_AVR)/cores/arduino
# The Leonardo variant has the Fio v3's pin map.
ARDUINO_VARIANT := $(ARDUINO_AVR)/variants/leonardo
FW := $(BUILD)/firmware
# Budgets of the whole image (the Caterina bootloader leaves 28 672 B flash, the chip has 2 560 B
# SRAM); the rest of the SRAM is stack.
FW_FLASH_BUDGET := 16384
FW_RAM_BUDGET := 1024

# The image keeps the Arduino core's USB serial port (FW_USB=1): a host that opens it at 1200 baud
# and closes it resets the particle into its Caterina bootloader, so uploads need no button.
# FW_USB=0 leaves the USB stack out (about 3 KB of flash and 150 B of RAM less); that image
# needs the reset button pressed before each upload.
FW_USB ?= 1
FW_MCU := -mmcu=atmega32u4 -DF_CPU=8000000L -DARDUINO=10807 -DARDUINO_AVR_FIOV3 -DARDUINO_ARCH_AVR \
  -DUSB_VID=0x1B4F -DUSB_PID=0xF101 '-DUSB_PRODUCT="SparkFun Fio v3"' \
  $(if $(filter 0,$(FW_USB)),-DPARTICLE_NO_USB)
# -mcall-prologues shares register save/restore code between functions and -mrelax shortens
# calls and jumps at link time: together about 740 B of flash. -mstrict-X (X only for pointer
# increments), -fno-move-loop-invariants (no registers tied up across loops) and
# -fno-inline-small-functions (a small function called from several places stays one copy) take
# about 430 B more off the USB image, -fno-ipa-sra and -fno-jump-tables (switches as compare
# chains) another 110 B; each was measured alone and together, others tried gave nothing.
FW_SIZE_FLAGS := -mcall-prologues -mrelax -mstrict-X -fno-move-loop-invariants \
  -fno-inline-small-functions -fno-ipa-sra -fno-jump-tables
FW_OPT := -Os -flto -ffunction-sections -fdata-sections $(FW_SIZE_FLAGS) -MMD -MP
# gcc 5.4 defines DECIMAL_DIG only for C, and the core's WString.cpp needs it.
FW_CXX_ONLY := -std=gnu++11 -fno-exceptions -fno-threadsafe-statics -DDECIMAL_DIG=__DECIMAL_DIG__
FW_CORE_INCLUDES := -I$(ARDUINO_CORE) -I$(ARDUINO_VARIANT)
# Our own code builds warning-free; the Arduino core is compiled as shipped.
FW_OWN_WARNINGS := -Wall -Wextra -Werror
FW_LOGIC_SOURCES ?= $(filter-out firmware/lib/capi/%,$(LOGIC_SOURCES))
FW_LOGIC_INCLUDES ?= $(filter-out -Ifirmware/lib/capi,$(LOGIC_INCLUDES))

# Rewritten only when the flags change, so that changing FW_USB (say) rebuilds what it affects.
FW_FLAGS_STAMP := $(FW)/flags.stamp
FW_FLAGS_TEXT := $(FW_MCU) $(FW_OPT) $(FW_CXX_ONLY) $(FW_OWN_WARNINGS) $(FW_LOGIC_INCLUDES)
$(FW_FLAGS_STAMP): FORCE
	@mkdir -p $(@D)
	@echo '$(FW_FLAGS_TEXT)' | cmp -s - $@ || echo '$(FW_FLAGS_TEXT)' > $@

FORCE:
.PHONY: FORCE

FW_CORE_SOURCES := $(wildcard $(ARDUINO_CORE)/*.c $(ARDUINO_CORE)/*.cpp $(ARDUINO_CORE)/*.S)
FW_CORE_OBJECTS := $(patsubst $(ARDUINO_CORE)/%,$(FW)/core/%.o,$(FW_CORE_SOURCES))
FW_LOGIC_OBJECTS := $(patsubst %,$(FW)/obj/%.o,$(FW_LOGIC_SOURCES))
# The wiring besides main.cpp (the USB upload port).
FW_WIRING_OBJECTS := $(patsubst %,$(FW)/obj/%.o,$(filter-out firmware/src/main.cpp,$(wildcard firmware/src/*.cpp)))

$(FW)/core/%.c.o: $(ARDUINO_CORE)/%.c $(FW_FLAGS_STAMP) | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(AVR_CC) $(FW_MCU) $(FW_OPT) -std=gnu11 $(FW_CORE_INCLUDES) -c -o $@ $<

$(FW)/core/%.cpp.o: $(ARDUINO_CORE)/%.cpp $(FW_FLAGS_STAMP) | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(AVR_CXX) $(FW_MCU) $(FW_OPT) $(FW_CXX_ONLY) $(FW_CORE_INCLUDES) -c -o $@ $<

$(FW)/core/%.S.o: $(ARDUINO_CORE)/%.S $(FW_FLAGS_STAMP) | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(AVR_CC) $(FW_MCU) -x assembler-with-cpp -MMD -MP $(FW_CORE_INCLUDES) -c -o $@ $<

# An archive, so that only the core objects the firmware uses are linked: linked directly, unused
# ones (Tone, WInterrupts) would bring their interrupt vectors along.
$(FW)/core/core.a: $(FW_CORE_OBJECTS)
	rm -f $@
	$(AVR_AR) rcs $@ $^

$(FW)/obj/%.cpp.o: %.cpp $(FW_FLAGS_STAMP) | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(AVR_CXX) $(FW_MCU) $(FW_OPT) $(FW_CXX_ONLY) $(FW_OWN_WARNINGS) $(FW_CORE_INCLUDES) \
	  $(FW_LOGIC_INCLUDES) -c -o $@ $<

# The fault-injection build differs from the normal one in main.cpp only.
$(FW)/faults/%.cpp.o: %.cpp $(FW_FLAGS_STAMP) | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(AVR_CXX) $(FW_MCU) $(FW_OPT) $(FW_CXX_ONLY) $(FW_OWN_WARNINGS) $(FW_CORE_INCLUDES) \
	  $(FW_LOGIC_INCLUDES) -DPARTICLE_FAULT_INJECTION -c -o $@ $<

FW_LINK = $(AVR_CXX) $(FW_MCU) -Os -flto -fuse-linker-plugin $(FW_SIZE_FLAGS) -Wl,--gc-sections \
  -o $@ $^ -lm

$(FW)/particle.elf: $(FW)/obj/firmware/src/main.cpp.o $(FW_WIRING_OBJECTS) $(FW_LOGIC_OBJECTS) \
    $(FW)/core/core.a
	$(FW_LINK)

$(FW)/particle-faults.elf: $(FW)/faults/firmware/src/main.cpp.o $(FW_WIRING_OBJECTS) \
    $(FW_LOGIC_OBJECTS) $(FW)/core/core.a
	$(FW_LINK)

$(FW)/%.hex: $(FW)/%.elf
	$(AVR_OBJCOPY) -O ihex -R .eeprom $< $@

# Prints flash (.text + .data) and static RAM (.data + .bss + .noinit) against the budgets. Over
# budget it warns (tests/sim fails then) but keeps the image, so the emulator tests still run;
# FW_STRICT=1 makes it an error.
FW_STRICT ?= 0
define fw_check_size
	@$(AVR_SIZE) -C --mcu=atmega32u4 $(1) | grep -E 'Program|Data'
	@set -- $$($(AVR_SIZE) -A $(1) | awk '$$1 == ".text" {t = $$2} $$1 == ".data" {d = $$2} \
	    $$1 == ".bss" {b = $$2} $$1 == ".noinit" {n = $$2} END {print t + d, d + b + n}'); \
	printf '%s: flash %d of %d B budget, static RAM %d of %d B budget\n' \
	  $(1) $$1 $(FW_FLASH_BUDGET) $$2 $(FW_RAM_BUDGET); \
	if [ $$1 -gt $(FW_FLASH_BUDGET) ] || [ $$2 -gt $(FW_RAM_BUDGET) ]; then \
	  echo "WARNING: $(1) is over its budget" >&2; [ "$(FW_STRICT)" = 0 ]; fi
endef

firmware: $(BUILD)/.system-deps $(FW)/particle.elf $(FW)/particle.hex
	$(call fw_check_size,$(FW)/particle.elf)

firmware-faults: $(BUILD)/.system-deps $(FW)/particle-faults.elf
	$(call fw_check_size,$(FW)/particle-faults.elf)

-include $(shell find $(FW) -name '*.d' 2>/dev/null)

# ---- firmware in the loop: simavr harness ------------------------------------------------------

SIM_CC := gcc
SIM_CFLAGS := -std=gnu11 -O2 -Wall -Wextra -Werror

# simavr's headers are included as system headers so that -Wextra judges only our code.
$(BUILD)/sim/particle_sim: host/particlebot/sim/particles/emulated/particle_sim.c | $(BUILD)/.system-deps
	@mkdir -p $(@D)
	$(SIM_CC) $(SIM_CFLAGS) $$(pkg-config --cflags-only-I simavr | sed 's/-I/-isystem /g') \
	  -o $@ $< $$(pkg-config --libs simavr) -lelf

harness: $(BUILD)/.system-deps $(BUILD)/sim/particle_sim

# ---- checks -------------------------------------------------------------------------------------

lint: $(VENV)/.installed $(BUILD)/.system-deps
	$(VENV)/bin/ruff check host tests tools benchmarks research docs/_hooks
	$(VENV)/bin/ruff format --check host tests tools benchmarks research docs/_hooks
	$(VENV)/bin/mypy
	clang-format --dry-run --Werror $$(git ls-files 'firmware/*.cpp' 'firmware/*.h' 'host/*.c')

format: $(VENV)/.installed
	$(VENV)/bin/ruff format host tests tools benchmarks research docs/_hooks
	$(VENV)/bin/ruff check --fix host tests tools benchmarks research docs/_hooks
	clang-format -i $$(git ls-files 'firmware/*.cpp' 'firmware/*.h' 'host/*.c')

ASAN_RUNTIME = $(shell $(NATIVE_CXX) -print-file-name=libasan.so)

# Firmware-logic tests run against the sanitized library; everything else against the release one.
pytest: $(VENV)/.installed native native-asan firmware firmware-faults harness
	LD_PRELOAD=$(ASAN_RUNTIME) ASAN_OPTIONS=detect_leaks=0 \
	  PARTICLEBOT_NATIVE_LIB=$(BUILD)/native-asan/libparticle.so \
	  $(VENV)/bin/pytest -q tests/firmware
	$(VENV)/bin/pytest -q --ignore=tests/firmware tests

# ---- documentation site (mkdocs.yml, sources in docs/) --------------------------------------------
# --strict turns a broken link, a missing page or a command whose --help no page shows into an error.

docs: $(VENV)/.installed
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet
	@echo "the site is in $(BUILD)/site: open $(BUILD)/site/index.html"

docs-check: $(VENV)/.installed
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet --site-dir $(BUILD)/site-check

test: system-deps venv check-generated lint cpp-test fuzz docs-check pytest

# The fast tier (pyproject.toml names the markers): what an edit is checked with before
# `make test` runs every tier. The firmware-logic tests run against the release library here.
FAST_TIER := not (simavr or dask or e2e or slow)
check: $(VENV)/.installed native cpp-test
	$(VENV)/bin/pytest -q -m '$(FAST_TIER)' tests

# setup compiles the simulator's kernels first, with progress, when numba's cache lacks them.
demo: system-deps venv native
	$(VENV)/bin/particlebot setup
	$(VENV)/bin/particlebot demo
	@echo "particlebot and pio are in $(VENV)/bin: run '. $(VENV)/bin/activate' to call them by name"

bench: venv native firmware firmware-faults harness
	$(VPY) benchmarks/bench.py

clean:
	rm -rf $(BUILD)
