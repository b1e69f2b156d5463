# SPDX-License-Identifier: Apache-2.0
# The LIE toolchain.  `make demo` and `make test` are the two commands;
# see README.md.  Objects go to build/<variant>/, binaries to bin/.
#
#   make            build bin/lie-render (and the other tools as they land)
#   make deps       install the Debian packages and the npm checks this project needs (only missing ones)
#   make demo       deps + build + render tests/scenes/museum1.gltf to out/
#   make test       deps + unit tests, tool tests, then the same under ASan+UBSan
#   make bench      benchmarks (prints ratios measured side by side, writes JSON)
#   make scenes     regenerate the bundled scenes under tests/scenes/
#   make fuzz       run every fuzz target for a bounded time (clang, libFuzzer)
#   make test-valgrind  the tool pipeline under valgrind memcheck (slow)

CC       ?= cc
CXX      ?= c++
VARIANT  ?= release
BUILD    := build/$(VARIANT)
# Baseline x86-64 by default, so the tools run on every CPU Debian supports; the hot kernels
# carry their own AVX2 clones, chosen at load time (LIE_HOT in lib/core/core.h).  ARCHFLAGS is
# for a build that runs on one machine only (ARCHFLAGS=-march=native); `make VARIANT=v3` is the
# whole build at -march=x86-64-v3, which bench/arch.sh compares against.
ARCHFLAGS ?=
WERROR   ?= -Werror
WARN     := -Wall -Wextra -Wshadow -Wno-unused-parameter $(WERROR)
OPT_release := -O3 -g
OPT_v3      := -O3 -g -march=x86-64-v3
OPT_asan    := -O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all
OPT      := $(OPT_$(VARIANT))
# The libraries, from pkg-config where Debian ships a module (lie.pc's Requires.private names
# the same ones); Embree 3 has none in Debian, so -lembree3 stays a bare flag.  OpenEXR's module
# lists its C++ libraries too: --as-needed keeps only OpenEXRCore, the one lib/image calls.
PC_DEPS  := OpenEXR yaml-0.1 libpng zlib libxxhash tinygltf stb
PC_CFLAGS := $(shell pkg-config --cflags $(PC_DEPS))
PC_LIBS  := $(shell pkg-config --libs $(PC_DEPS))
LIBS_PRIVATE := -lembree3 -lpthread -lm -lstdc++
# -fno-math-errno and -fno-trapping-math let the shading loops vectorise; -ffp-contract=off keeps results identical
# whichever way a loop is vectorised, and between the baseline code and the AVX2 clones.  -fopenmp-simd enables
# `#pragma omp simd` only.
COMMON   := $(OPT) $(ARCHFLAGS) $(WARN) -DTEST_SCENES=\"$(CURDIR)/tests/scenes\" -fno-math-errno -fno-trapping-math -ffp-contract=off -fopenmp-simd \
            -D_GNU_SOURCE -Ilib $(PC_CFLAGS) -MMD -MP
# The project's flags come first and the user's CFLAGS, CXXFLAGS, CPPFLAGS and LDFLAGS after
# them, so `make CFLAGS=-O2` changes the optimisation and keeps -std=c11 -Ilib (GNU make's
# command-line variables would otherwise replace the project's).
LIE_CFLAGS   := -std=c11 $(COMMON)
LIE_CXXFLAGS := -std=c++17 $(COMMON) -I/usr/include/stb -I/usr/include/nlohmann
LIE_LDFLAGS  := $(filter -fsanitize=%,$(OPT)) -Wl,--as-needed
LIE_LIBS     := -lembree3 $(PC_LIBS) -lpthread -lm -lstdc++
# what the tools and test programs link with: the project's libraries and the user's LDLIBS
LDLIBS_ALL    = $(LIE_LIBS) $(LDLIBS)
CC_C   = $(CC) $(LIE_CFLAGS) $(CPPFLAGS) $(CFLAGS)
CC_CXX = $(CXX) $(LIE_CXXFLAGS) $(CPPFLAGS) $(CXXFLAGS)
CC_LD  = $(CC) $(LIE_LDFLAGS) $(LDFLAGS)

LIB_C    := $(sort $(filter-out lib/dist/%,$(wildcard lib/*/*.c)))
LIB_CXX  := $(sort $(wildcard lib/*/*.cpp))
# lib/shade's LTC tables are data (lib/shade/ltc_table.dat), made C here (scripts/ltc-table.awk)
LIB_OBJ  := $(LIB_C:%.c=$(BUILD)/%.o) $(LIB_CXX:%.cpp=$(BUILD)/%.o) $(BUILD)/gen/ltc_table.o
LIB_A    := $(BUILD)/liblie.a
# The shared library: SONAME liblie.so.MAJOR, only the lie_ symbols of the public headers
# exported (-fvisibility=hidden, the headers' `visibility push(default)`, lib/liblie.map).
SOVERSION := 0
LIBVERSION := 0.1.0
LIB_SO   := $(BUILD)/liblie.so.$(LIBVERSION)
# The library's objects are position-independent, so one set serves liblie.a and liblie.so.
$(LIB_OBJ): LIE_CFLAGS += -fPIC -fvisibility=hidden -fno-semantic-interposition
$(LIB_OBJ): LIE_CXXFLAGS += -fPIC -fvisibility=hidden -fvisibility-inlines-hidden -fno-semantic-interposition

# tools/common is linked into every tool and test helper, not built as a tool.
TOOLS    := $(filter-out common,$(notdir $(wildcard tools/*)))
COMMON_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(wildcard tools/common/*.c))
BINDIR   := $(if $(filter release,$(VARIANT)),bin,$(BUILD)/bin)
TOOL_BIN := $(TOOLS:%=$(BINDIR)/%)

UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/tests/%)

.PHONY: all deps demo test test-unit test-tools test-asan test-valgrind bench bench-build bench-build-scenes bench-mpi bench-view scenes fuzz clean \
        install uninstall man shared ltc-tables ltc-bench print-libs
all: $(TOOL_BIN)

deps:
	@sh scripts/deps.sh

# Every object depends on the flags it is compiled with: $(BUILD)/flags.txt is rewritten when
# they change (ARCHFLAGS, CFLAGS=..., another compiler), so no object of other flags survives.
BUILD_FLAGS := $(CC_C) | $(CC_CXX)
$(BUILD)/flags.txt: FORCE
	@mkdir -p $(dir $@)
	@echo '$(subst ','\'',$(BUILD_FLAGS))' | cmp -s - $@ || echo '$(subst ','\'',$(BUILD_FLAGS))' > $@

$(BUILD)/%.o: %.c $(BUILD)/flags.txt
	@mkdir -p $(dir $@)
	$(CC_C) -c $< -o $@
$(BUILD)/%.o: %.cpp $(BUILD)/flags.txt
	@mkdir -p $(dir $@)
	$(CC_CXX) -c $< -o $@

$(BUILD)/gen/ltc_table.c: lib/shade/ltc_table.dat scripts/ltc-table.awk
	@mkdir -p $(dir $@)
	awk -f scripts/ltc-table.awk $< > $@.tmp && mv $@.tmp $@
$(BUILD)/gen/ltc_table.o: $(BUILD)/gen/ltc_table.c $(BUILD)/flags.txt
	@mkdir -p $(dir $@)
	$(CC_C) -c $< -o $@

$(LIB_A): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(LIB_SO): $(LIB_OBJ) lib/liblie.map
	$(CC_LD) -shared -Wl,-soname,liblie.so.$(SOVERSION) -Wl,--version-script=lib/liblie.map \
	    -Wl,--no-undefined $(LIB_OBJ) $(LDLIBS_ALL) -o $@
shared: $(LIB_SO)

# The commit goes into one object only, rebuilt when HEAD (or the dirty state) changes.
COMMIT := $(shell git describe --always --dirty 2>/dev/null || echo unknown)
$(BUILD)/commit.txt: FORCE
	@mkdir -p $(dir $@)
	@echo '$(COMMIT)' | cmp -s - $@ || echo '$(COMMIT)' > $@
$(BUILD)/lib/version/version.o: $(BUILD)/commit.txt
$(BUILD)/lib/version/version.o: LIE_CFLAGS += -DLIE_COMMIT=\"$(COMMIT)\"
.PHONY: FORCE
FORCE:

# A tool links every object of its folder (tools/NAME/*.c).
TOOL_OBJ = $(patsubst %.c,$(BUILD)/%.o,$(wildcard tools/$(1)/*.c))
.SECONDEXPANSION:
# tools/common/cli.h: for the tools, the test helpers and lib/dist (linked into tools only)
$(BUILD)/tools/%.o $(BUILD)/tests/helpers/%.o $(BUILD)/lib/dist/%.o: LIE_CFLAGS += -Itools
$(BINDIR)/%: $$(call TOOL_OBJ,$$*) $(COMMON_OBJ) $(LIB_A)
	@mkdir -p $(dir $@)
	$(CC_LD) $^ $(LDLIBS_ALL) -o $@
.SECONDARY:

# lie-view opens a window with SDL2 (its software renderer: no GPU needed).
SDL_CFLAGS := $(shell sdl2-config --cflags 2>/dev/null)
SDL_LIBS   := $(shell sdl2-config --libs 2>/dev/null)
$(BUILD)/tools/lie-view/%.o: LIE_CFLAGS += $(SDL_CFLAGS)
$(BINDIR)/lie-view: LIE_LIBS += $(SDL_LIBS)

# lib/dist: the MPI layer (Open MPI), linked into lie-render and lie-build
# only; without mpirun it never calls MPI (lib/dist/dist.h).
MPI_CFLAGS := $(shell mpicc --showme:compile 2>/dev/null)
MPI_LIBS   := $(shell mpicc --showme:link 2>/dev/null)
MPI_TOOLS  := lie-render lie-build
DIST_A     := $(BUILD)/liblie_dist.a
$(BUILD)/lib/dist/%.o $(BUILD)/tools/lie-render/dist.o $(BUILD)/tools/lie-build/dist.o: LIE_CFLAGS += $(MPI_CFLAGS)
$(DIST_A): $(patsubst %.c,$(BUILD)/%.o,$(wildcard lib/dist/*.c))
	@rm -f $@
	ar rcs $@ $^
$(MPI_TOOLS:%=$(BINDIR)/%): $(DIST_A)
$(MPI_TOOLS:%=$(BINDIR)/%): LIE_LIBS := $(DIST_A) $(LIB_A) $(MPI_LIBS) $(LIE_LIBS)

$(BUILD)/tests/%: $(BUILD)/tests/unit/%.o $(LIB_A)
	@mkdir -p $(dir $@)
	$(CC_LD) $^ $(LDLIBS_ALL) -lcmocka -o $@

# ---- test helpers (not installed tools) ------------------------------------
HELPERS  := $(patsubst tests/helpers/%.c,$(BUILD)/tests/%,$(wildcard tests/helpers/*.c))
$(BUILD)/tests/%: $(BUILD)/tests/helpers/%.o $(COMMON_OBJ) $(LIB_A)
	@mkdir -p $(dir $@)
	$(CC_LD) $^ $(LDLIBS_ALL) -o $@
# the tool tests' generated fixtures write glTF with the scenes' writer
$(BUILD)/tests/blocker-scenes: $(BUILD)/tests/scenes/gen/gen_gltf.o

# ---- scenes -------------------------------------------------------------
GEN := $(BUILD)/gen_scenes
$(GEN): $(BUILD)/tests/scenes/gen/gen_scenes.o $(BUILD)/tests/scenes/gen/gen_gltf.o
	$(CC) $(LDFLAGS) $^ -lpng -lz -lm -o $@
scenes: $(GEN)
	$(GEN) tests/scenes
# the bench's 250k-triangle atrium (bench/atrium.c), generated under out/, never committed
ATRIUM_GEN := $(BUILD)/atrium-gen
$(ATRIUM_GEN): $(BUILD)/bench/atrium.o $(BUILD)/tests/scenes/gen/gen_gltf.o
	$(CC) $(LDFLAGS) $^ -lpng -lz -lm -o $@

# the equal-quality bench's Lambertian copies of the third-party scenes (bench/lambert.c)
BENCH_LAMBERT := $(BUILD)/bench-lambert
$(BENCH_LAMBERT): $(BUILD)/bench/lambert.o $(LIB_A)
	$(CC_LD) $^ $(LDLIBS_ALL) -o $@

# what the best LIE could save on a scene, by an oracle (bench/light-classes.c)
BENCH_CLASSES := $(BUILD)/bench-light-classes
$(BENCH_CLASSES): $(BUILD)/bench/light-classes.o $(LIB_A)
	$(CC_LD) $^ $(LDLIBS_ALL) -o $@

# ---- LTC tables (lib/shade/ltc.h): fitted by scripts/ltc-fit.c, the data committed ----
LTC_FIT := $(BUILD)/ltc-fit
$(LTC_FIT): scripts/ltc-fit.c
	@mkdir -p $(dir $@)
	$(CC) -std=c11 -O2 -ffp-contract=off $(WARN) $< -lm -o $@
ltc-tables: $(LTC_FIT)
	$(LTC_FIT) -o lib/shade/ltc_table.dat.tmp && mv lib/shade/ltc_table.dat.tmp lib/shade/ltc_table.dat
ltc-bench: $(BUILD)/tests/ltc-bench
	$(BUILD)/tests/ltc-bench

# ---- the two commands -----------------------------------------------------
demo: deps
	$(MAKE) -j$(NPROC) all
	@mkdir -p out
	bin/lie-build tests/scenes/museum1.gltf -o out/museum1.lie
	bin/lie-render out/museum1.lie -o out/museum1.exr --stats
	bin/lie-render out/museum1.lie -o out/museum1.png -q
	@echo "demo: wrote $(CURDIR)/out/museum1.exr and $(CURDIR)/out/museum1.png (from the LIE cache out/museum1.lie)"

NPROC    := $(shell nproc 2>/dev/null || echo 2)

# Everything the tests need, built in parallel; the tests then run in order.
build-tests: $(TOOL_BIN) $(UNIT_BIN) $(HELPERS)

test: deps
	$(MAKE) -j$(NPROC) build-tests
	$(MAKE) test-unit test-tools
	$(MAKE) -j$(NPROC) VARIANT=asan build-tests
	$(MAKE) VARIANT=asan test-unit test-tools

test-unit: $(UNIT_BIN)
	@sh tests/run-unit.sh $(UNIT_BIN)

test-tools: $(TOOL_BIN) $(HELPERS)
	@BINDIR=$(BINDIR) HELPERS=$(BUILD)/tests sh tests/run-tools.sh

test-asan:
	$(MAKE) -j$(NPROC) VARIANT=asan build-tests
	$(MAKE) VARIANT=asan test-unit test-tools

bench: all build-tests
	@sh bench/run.sh
	@sh bench/build.sh
	@sh bench/arch.sh

# what a lie-build costs in full frames, per scene: the paper's rule against the cost rule
bench-build: all build-tests
	@sh bench/build.sh

# the same for the third-party scenes of ../shared/scenes alone (minutes: scifi_hallway)
bench-build-scenes: all build-tests
	@SCENES="$(wildcard ../shared/scenes/bedroom_corner/scene.gltf ../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf ../shared/scenes/scifi_hallway/space_ship_hallway.glb)" \
	  ATRIUM=0 PAPER=0 ONE=0 BREAKEVEN=1 MANYLIGHTS=0 VIEW_SCENES=" " sh bench/build.sh

# lie-view's interactive loop under Xvfb (not a timed test: figures depend on the load)
bench-view: all
	@sh bench/view.sh

# lie-render and lie-build under mpirun against one process (docs/mpi.md)
bench-mpi: all
	@sh bench/mpi.sh

fuzz:
	@sh tests/fuzz/run.sh

# what a program linking liblie.a needs (tests/fuzz/run.sh)
print-libs:
	@echo '$(LIE_LIBS)'

# The pipeline lie-build | rst-update | lie-render (and lie-inspect) under
# valgrind's memcheck: slow, so not part of `make test`.
test-valgrind: all
	@BINDIR=bin sh tests/valgrind.sh

clean:
	rm -rf build bin out

include mk/install.mk

-include $(shell find build -name '*.d' 2>/dev/null)
