# Skeleton-guided path tracing toolchain.
#   make            build bin/voxelize bin/skeletonize bin/importance bin/render bin/merge
#   make test       install missing packages, build, run every test
#   make demo       install missing packages, build, run the pipeline on data/corridor
#   make scene SCENE=path/to/scene.json   build out/NAME/ (only steps whose inputs changed)
#   make farm SCENE=... SHARDS=4          the render in shards on Slurm (or here), merged
#   make bench      speed and error benchmarks, writes bench/report.md (bench-quick, bench-long);
#                   builds the Open PGL peer first (scripts/build-openpgl.sh) for render --sampling openpgl
#   make openpgl    build the Open PGL peer once (build/openpgl) and render --sampling openpgl
#   make SANITIZE=1 ...  the same with AddressSanitizer + UBSan in build/asan

SHELL := /bin/bash
CC ?= cc
CXX ?= c++
ifeq ($(origin CC),default)
CC := cc
endif
ifeq ($(origin CXX),default)
CXX := c++
endif

ifeq ($(FUZZ),1)
# libFuzzer builds: everything instrumented with clang for coverage.
CC := clang
CXX := clang++
BUILD ?= build/fuzz
SANFLAGS := -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
OPT := -O1
else ifeq ($(SANITIZE),1)
BUILD ?= build/asan
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
OPT := -O1
# line tables only: a sanitizer's report still names file and line, and
# the build every make test makes takes 9 s less (86 -> 77 s on 2 cores)
DEBUG := -g1
else
BUILD ?= build/release
OPT := -O2
endif
DEBUG ?= -g
BIN ?= bin
ifneq ($(filter 1,$(SANITIZE) $(FUZZ)),)
BIN := $(BUILD)/bin
endif

WARN := -Wall -Wextra
CPPFLAGS += -Icommon -I. -D_GNU_SOURCE -MMD -MP
CFLAGS += -std=c11 $(OPT) $(DEBUG) $(WARN) $(SANFLAGS) -pthread
CXXFLAGS += -std=c++17 $(OPT) $(DEBUG) $(WARN) $(SANFLAGS) -pthread -Wno-deprecated-declarations
LDFLAGS += $(SANFLAGS) -pthread
LDLIBS := -lembree3 -lopenvdb -ltbb -lassimp -lcjson -lexpat -lz -ldl \
          -lOpenEXR-3_1 -lIex-3_1 -lImath-3_1 \
          -lcriterion -lstdc++ -lm

# The Open PGL peer (render --sampling openpgl): linked where `make openpgl`
# built it (or OPENPGL_DIR names an installed one); without it
# render/guides/openpgl_field.cpp compiles to a stub that says how to get it.
OPENPGL_PREFIX := $(if $(OPENPGL_DIR),$(OPENPGL_DIR),build/openpgl/install)
ifneq ($(wildcard $(OPENPGL_PREFIX)/include/openpgl/openpgl.h),)
OPENPGL_CPPFLAGS := -DSG_HAVE_OPENPGL -isystem $(OPENPGL_PREFIX)/include
LDLIBS += -L$(OPENPGL_PREFIX)/lib -Wl,-rpath,$(abspath $(OPENPGL_PREFIX)/lib) -lopenpgl
endif
PROG_LDLIBS := $(filter-out -lcriterion,$(LDLIBS))

ALL_STEPS := voxelize skeletonize importance render merge
# A step joins the build once it has a main.c.
STEPS := $(foreach s,$(ALL_STEPS),$(if $(wildcard $(s)/main.c),$(s)))
PROGRAMS := $(addprefix $(BIN)/,$(STEPS))

# OpenImageIO's two wrappers are a shared object of their own, loaded on
# first use (common/image_library.h): linked in, OpenImageIO's 250 shared
# objects cost every program half a second of CPU at start. The objects are
# built position-independent, with their own copies of the helpers they call.
IMAGES_CXX := common/image_io.cpp render/texture_images.cpp
IMAGES_SO := $(BUILD)/libsg_images.so
IMAGES_OBJ := $(IMAGES_CXX:%.cpp=$(BUILD)/pic/%.o) $(BUILD)/pic/common/error.o $(BUILD)/pic/common/output_file.o
# EXR through OpenEXR itself, linked in (common/exr_file.h)
$(BUILD)/common/exr_file.o: CPPFLAGS += -isystem /usr/include/OpenEXR -isystem /usr/include/Imath
$(BUILD)/common/image_library.o: CPPFLAGS += -DSG_IMAGES_LIBRARY='"$(abspath $(IMAGES_SO))"'

COMMON_C := $(wildcard common/*.c common/*/*.c)
COMMON_CXX := $(filter-out $(IMAGES_CXX),$(wildcard common/*.cpp))
COMMON_OBJ := $(COMMON_C:%.c=$(BUILD)/%.o) $(COMMON_CXX:%.cpp=$(BUILD)/%.o)

# Each step: its library (every .c and .cpp but main.c, in its folder and
# the folders inside it) and its program (main.c).
step_lib_src = $(filter-out $(1)/main.c $(IMAGES_CXX),$(wildcard $(1)/*.c $(1)/*.cpp $(1)/*/*.c $(1)/*/*.cpp))
step_lib_obj = $(patsubst %.cpp,$(BUILD)/%.o,$(patsubst %.c,$(BUILD)/%.o,$(call step_lib_src,$(1))))
STEP_LIBS := $(foreach s,$(STEPS),$(BUILD)/lib$(s).a)

TEST_SRC := $(wildcard tests/test_*.c)
TEST_SUPPORT_SRC := $(filter-out $(TEST_SRC),$(wildcard tests/*.c))
# the longest suites start first (tests/run-tests.sh runs them side by
# side): a long one started last would run alone at the end
TEST_SLOW := test_render_farm test_stress test_render_integrator test_merge test_pbrt_scene \
             test_render_budget test_render_pipeline test_render_sampling test_skeleton test_render_field
TEST_NAMES := $(TEST_SRC:tests/%.c=%)
TEST_BIN := $(patsubst %,$(BUILD)/tests/%,$(foreach t,$(TEST_SLOW),$(filter $(t),$(TEST_NAMES))) \
              $(filter-out $(TEST_SLOW),$(TEST_NAMES)))
# The farm suite drives Slurm and the farm script (a cluster started for it,
# jobs, a cancelled shard): it waits on the scheduler far more than it runs
# code, and the programs its jobs run are the ones test_merge and
# test_render_pipeline run under the sanitizers. So it runs in the
# optimized pass only (under the sanitizers it took 122 s of a fresh
# clone's 570 s of make test, 52 s of it CPU).
TEST_UNSANITIZED := test_render_farm
ifeq ($(SANITIZE),1)
TEST_BIN := $(filter-out $(patsubst %,$(BUILD)/tests/%,$(TEST_UNSANITIZED)),$(TEST_BIN))
endif
TEST_SUPPORT_OBJ := $(TEST_SUPPORT_SRC:%.c=$(BUILD)/%.o)
# tests find the repository's data files from any working directory
$(BUILD)/tests/support_files.o: CPPFLAGS += -DSG_SOURCE_ROOT='"$(CURDIR)"'
# support_criterion.o is linked whole into every test (it replaces a libc
# function); the other helpers come from an archive, so that a test links
# only what it calls.
TEST_CRITERION_OBJ := $(BUILD)/tests/support_criterion.o
# Not instrumented: AddressSanitizer calls dl_iterate_phdr while it starts,
# before instrumented code may run.
$(TEST_CRITERION_OBJ): SANFLAGS :=
$(TEST_BIN): $(TEST_CRITERION_OBJ) # named here, so that make keeps it and remakes it

# Benchmarks: each bench/*.c is a program; bench/run.sh drives them. Their
# shared code (bench/lib/) is an archive they link, as do its tests.
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)
BENCH_LIB := $(BUILD)/libbench.a
BENCH_LIB_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(wildcard bench/lib/*.c))

.PHONY: all test test-programs check-tests demo scene farm bench bench-build bench-quick bench-long deps bench-deps fuzz fuzz-run clean distclean \
        openpgl FORCE
.DEFAULT_GOAL := all

all: $(PROGRAMS)

$(IMAGES_SO): $(IMAGES_OBJ)
	$(CXX) -shared $(LDFLAGS) -Wl,-Bsymbolic -o $@ $^ -lOpenImageIO -lOpenImageIO_Util
$(BUILD)/pic/%.o: %.cpp
	@mkdir -p $(@D)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -fPIC -c -o $@ $<
$(BUILD)/pic/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS) -fPIC -c -o $@ $<

# Rebuilt from scratch so that the object of a removed source does not stay
# in it; ar names members by file name alone, so no two sources in common/
# and its folders may share one.
$(BUILD)/libcommon.a: $(COMMON_OBJ)
	@mkdir -p $(@D)
	rm -f $@
	$(AR) rcs $@ $^

define STEP_RULES
$(BUILD)/lib$(1).a: $(call step_lib_obj,$(1))
	@mkdir -p $$(@D)
	rm -f $$@
	$$(AR) rcs $$@ $$^
$(BIN)/$(1): $(BUILD)/$(1)/main.o $(BUILD)/lib$(1).a $(STEP_LIBS) $(BUILD)/libcommon.a | $(IMAGES_SO)
	@mkdir -p $$(@D)
	$$(CC) $$(LDFLAGS) -o $$@ $(BUILD)/$(1)/main.o $(STEP_LIBS) $(BUILD)/libcommon.a $$(PROG_LDLIBS)
endef
$(foreach s,$(STEPS),$(eval $(call STEP_RULES,$(s))))

$(BUILD)/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c -o $@ $<

$(BUILD)/%.o: %.cpp
	@mkdir -p $(@D)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -c -o $@ $<

# The shim is the one file that sees Open PGL: it is rebuilt when the peer
# comes or goes (the stamp holds the flags, rewritten only when they change).
$(BUILD)/render/guides/openpgl_field.o: CPPFLAGS += $(OPENPGL_CPPFLAGS)
$(BUILD)/render/guides/openpgl_field.o: $(BUILD)/openpgl.flags
$(BUILD)/openpgl.flags: FORCE
	@mkdir -p $(@D)
	@echo '$(OPENPGL_CPPFLAGS)' > $@.new
	@if cmp -s $@.new $@; then rm -f $@.new; else mv $@.new $@; fi

openpgl:
	@bash scripts/build-openpgl.sh
	@$(MAKE) --no-print-directory all

$(BENCH_LIB): $(BENCH_LIB_OBJ)
	@mkdir -p $(@D)
	rm -f $@
	$(AR) rcs $@ $^
$(BUILD)/tests/test_bench_convergence $(BUILD)/tests/test_error_metrics: $(BENCH_LIB)
# the skeleton benchmark measures on the tests' synthetic media (tests/support_shapes.c)
$(BUILD)/bench/skeleton_bench: $(BUILD)/libtestsupport.a

$(BUILD)/libtestsupport.a: $(filter-out $(TEST_CRITERION_OBJ),$(TEST_SUPPORT_OBJ))
	@mkdir -p $(@D)
	rm -f $@
	$(AR) rcs $@ $^

# --as-needed: a test binary loads only the shared libraries it calls.
# Criterion starts a process for every test, so what every process loads
# counts (OpenImageIO's 250 shared objects come only with an image: see
# IMAGES_SO).
$(BUILD)/tests/%: $(BUILD)/tests/%.o $(TEST_CRITERION_OBJ) $(BUILD)/libtestsupport.a $(STEP_LIBS) $(BUILD)/libcommon.a | $(IMAGES_SO)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -Wl,--as-needed -o $@ $< $(TEST_CRITERION_OBJ) $(BUILD)/libtestsupport.a $(filter $(BENCH_LIB),$^) $(STEP_LIBS) \
	  $(BUILD)/libcommon.a $(LDLIBS)

$(BUILD)/bench/%: $(BUILD)/bench/%.o $(BENCH_LIB) $(STEP_LIBS) $(BUILD)/libcommon.a | $(IMAGES_SO)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $< $(filter %/libtestsupport.a,$^) $(BENCH_LIB) $(STEP_LIBS) $(BUILD)/libcommon.a $(PROG_LDLIBS)

# The benchmarks render the peer too: Open PGL is built first (cached), then
# a sub-make builds the programs, which links it only when this make's parse
# finds build/openpgl/install (hence not plain prerequisites). When the peer
# cannot be built, the benchmarks run without it and the report says so.
bench-build: bench-deps
	@bash scripts/build-openpgl.sh || echo "bench: Open PGL could not be built: the benchmarks run without openpgl"
	@$(MAKE) --no-print-directory $(PROGRAMS) $(BENCH_BIN)

bench: bench-build
	@SG_BIN=$(abspath $(BIN)) SG_BENCH_BIN=$(abspath $(BUILD)/bench) bash bench/run.sh

bench-quick: bench-build
	@SG_QUICK=1 SG_BIN=$(abspath $(BIN)) SG_BENCH_BIN=$(abspath $(BUILD)/bench) bash bench/run.sh

# publication-quality numbers: 60 s runs, 5 seeds, 4x the pixels (about 3.5 hours)
bench-long: bench-build
	@SG_LONG=1 SG_BIN=$(abspath $(BIN)) SG_BENCH_BIN=$(abspath $(BUILD)/bench) bash bench/run.sh

# make fuzz: every tests/fuzz/fuzz_*.c is a libFuzzer target; each runs for
# FUZZ_SECONDS from its seed corpus tests/fuzz/corpus/NAME/ (new inputs go
# to build/fuzz/corpus/NAME/, crashes to build/fuzz/crashes/).
FUZZ_SRC := $(wildcard tests/fuzz/fuzz_*.c)
FUZZ_SECONDS ?= 60
# OpenVDB 10 loads raw file bytes into bools (undefined behaviour inside its
# headers, harmless in practice): gcc cannot exempt it from the source.
$(BUILD)/common/medium_vdb.o $(BUILD)/common/vdb_read_guard.o: CXXFLAGS += -fno-sanitize=bool

# Linked by the C++ driver: UBSan's C++ checks in the wrappers need its runtime.
$(BUILD)/fuzzers/%: $(BUILD)/tests/fuzz/%.o $(STEP_LIBS) $(BUILD)/libcommon.a | $(IMAGES_SO)
	@mkdir -p $(@D)
	$(CXX) $(LDFLAGS) -fsanitize=fuzzer -o $@ $< $(STEP_LIBS) $(BUILD)/libcommon.a $(PROG_LDLIBS)

fuzz: deps
	@$(MAKE) --no-print-directory FUZZ=1 -j$$(nproc) $(FUZZ_SRC:tests/fuzz/%.c=build/fuzz/fuzzers/%)
	@$(MAKE) --no-print-directory FUZZ=1 fuzz-run

fuzz-run:
	@mkdir -p $(BUILD)/crashes
	@for t in $(FUZZ_SRC:tests/fuzz/%.c=%); do \
	  mkdir -p $(BUILD)/corpus/$$t tests/fuzz/corpus/$$t; \
	  echo "== $$t ($(FUZZ_SECONDS) s)"; \
	  extra=; [ $$t = fuzz_medium_vdb ] && extra="-fork=1 -ignore_ooms=1"; \
	  ASAN_OPTIONS=allocator_may_return_null=1 UBSAN_OPTIONS=halt_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(abspath tests/lsan.supp) \
	  $(BUILD)/fuzzers/$$t -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=4096 \
	    -malloc_limit_mb=2000000 $$extra \
	    -artifact_prefix=$(BUILD)/crashes/$$t- $(BUILD)/corpus/$$t tests/fuzz/corpus/$$t \
	    2>&1 | grep -E "^#[0-9]+[[:space:]]+DONE|^==[0-9]+==|SUMMARY|artifact_prefix|Test unit written|oom/timeout/crash|INFO: fuzzed" ; \
	done; \
	if ls $(BUILD)/crashes/* >/dev/null 2>&1; then echo "fuzz: crashes in $(BUILD)/crashes/"; ls $(BUILD)/crashes; exit 1; fi

# Tests run from the repository root; they find bin/ through SG_BIN.
bench-deps:
	@SG_WITH_BENCH_TOOLS=1 bash scripts/install-deps.sh

deps:
	@bash scripts/install-deps.sh

# make test: the suites in an optimized build, then again under
# AddressSanitizer + UBSan (SG_SANITIZED=1 lets heavy tests scale down).
# The test binaries are built in parallel with the programs (check-tests
# alone would build them one at a time).
test: deps
	@$(MAKE) --no-print-directory -j$$(nproc) test-programs
	@$(MAKE) --no-print-directory check-tests
	@$(MAKE) --no-print-directory -j$$(nproc) SANITIZE=1 test-programs
	@SG_SANITIZED=1 $(MAKE) --no-print-directory SANITIZE=1 check-tests

test-programs: $(PROGRAMS) $(TEST_BIN)

check-tests: $(PROGRAMS) $(TEST_BIN)
	@echo "== tests in $(BUILD)"
	@$(if $(OPENPGL_CPPFLAGS),true,echo "tests: Open PGL is not built here (make openpgl builds it): its tests skip")
	@SG_BIN=$(abspath $(BIN)) bash tests/run-tests.sh $(TEST_BIN)

# make demo: the corridor through the four steps, then one picture that
# makes the point: bsdf, guided (and openpgl, where `make openpgl` built it)
# after the same 2 seconds beside a 30 s reference, each with its error.
demo: deps
	@$(MAKE) --no-print-directory all
	@$(MAKE) --no-print-directory scene SCENE=data/corridor/corridor.json
	@if [ -e out/corridor/image.png ]; then echo "demo: images in out/corridor/: image.png to look at, image.exr linear"; \
	else echo "demo: artifacts in out/corridor/: $$(ls out/corridor | tr '\n' ' ')"; fi
	@SG_BIN=$(BIN) bash scripts/demo-compare.sh data/corridor/corridor.json out/corridor/importance.cache \
	  out/corridor/compare

# ---- scene builds -------------------------------------------------------
# out/NAME/geometry.key holds the identity of what the precompute depends on
# (geometry, lights, resolution: not the camera). It is rewritten only when
# that identity changes, so a moved camera re-renders without re-running the
# precompute.
ifdef SCENE
NAME := $(basename $(notdir $(SCENE)))
OUT := out/$(NAME)
VOXELIZE_FLAGS ?=
SCENE_OUTPUTS := $(OUT)/medium.vdb \
  $(if $(filter skeletonize,$(STEPS)),$(OUT)/skeleton.ply) \
  $(if $(filter importance,$(STEPS)),$(OUT)/importance.cache) \
  $(if $(filter render,$(STEPS)),$(OUT)/image.exr)
scene: $(SCENE_OUTPUTS)
	@echo "scene: $(OUT)/ holds $(notdir $(SCENE_OUTPUTS))"

$(OUT)/geometry.key: FORCE $(BIN)/voxelize
	@mkdir -p $(OUT)
	@$(BIN)/voxelize $(SCENE) --key $(VOXELIZE_FLAGS) > $@.new
	@if cmp -s $@.new $@; then rm -f $@.new; else mv $@.new $@; fi

$(OUT)/medium.vdb: $(OUT)/geometry.key $(BIN)/voxelize
	$(BIN)/voxelize $(SCENE) -o $@ $(VOXELIZE_FLAGS)

$(OUT)/skeleton.ply: $(OUT)/medium.vdb $(BIN)/skeletonize
	$(BIN)/skeletonize $< -o $@

$(OUT)/importance.cache: $(OUT)/medium.vdb $(OUT)/skeleton.ply $(BIN)/importance
	$(BIN)/importance $(OUT)/medium.vdb $(OUT)/skeleton.ply -o $@ --vectors $(OUT)/vectors.ply

# A sampling mode that learns (render --describe says: guided by default)
# learns within the image's own render, every pass of it kept in the image,
# and writes what it learned to out/NAME/field (render --save-field): a
# second render of the scene can start from it (RENDER_FLAGS="--field
# out/NAME/field ..."). RENDER_FLAGS="--sampling bsdf ..." learns nothing.
SCENE_MODE := $(shell set -- $(RENDER_FLAGS); while [ $$# -gt 0 ]; do [ "$$1" = --sampling ] && echo "$$2"; shift; done)
SCENE_DESCRIBE := $(shell [ -x $(BIN)/render ] && $(BIN)/render --describe | \
  grep -F '$(if $(SCENE_MODE),"name": "$(lastword $(SCENE_MODE))","default_with_cache": true)')
SCENE_SAVES_FIELD := $(if $(findstring "learns": true,$(SCENE_DESCRIBE)),$(if $(findstring --field,$(RENDER_FLAGS)),,yes))

$(OUT)/image.exr: $(SCENE) $(OUT)/importance.cache $(BIN)/render
	$(BIN)/render $(SCENE) --cache $(OUT)/importance.cache $(if $(SCENE_SAVES_FIELD),--save-field $(OUT)/field) \
	  -o $@ --png $(OUT)/image.png $(RENDER_FLAGS)

# make farm SCENE=... [SHARDS=4] [FARM_OUT=out/NAME/farm] [RENDER_FLAGS=...]:
# the render split into shards on Slurm (a controller answers), else here, and
# merged (scripts/slurm-render.sh; README "Rendering on a cluster").
SHARDS ?= 4
FARM_OUT ?= $(OUT)/farm
farm: $(PROGRAMS)
	@bash scripts/slurm-render.sh $(SCENE) --shards $(SHARDS) --out $(FARM_OUT) --bin $(BIN) -- $(RENDER_FLAGS)
else
scene farm:
	@echo "usage: make $@ SCENE=path/to/scene.json" >&2; exit 2
endif

FORCE:

# Keep intermediate objects (tests link from them) so nothing rebuilds needlessly.
.SECONDARY:

clean:
	rm -rf build bin

distclean: clean
	rm -rf out

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
