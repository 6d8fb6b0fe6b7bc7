# matremap — build, test, demo, benchmark and install. See README.md.
#
#   make            library (build/libmatremap.a) and tools (build/bin/)
#   make check      the test suite (every tests/test_*.c binary and tests/*.sh script)
#   make asan       the test suite built with AddressSanitizer + UndefinedBehaviorSanitizer
#   make demo       renders and compares the demo materials of data/ into out/demo
#   make bench      benchmarks (prints figures, asserts nothing; see docs/performance.md); one section:
#                   make bench BENCH_ARGS="--only report-accuracy"
#   make analyses   the paper's stability analyses (docs/analyses.md)
#   make paper      the paper's Appendix fits, Fig. 18 (a chain) and Fig. 19 (extrapolation) reproduced in
#                   build/paper (docs/paper-reproduction.md; 4-5 min on 2 cores)
#   make evaluation the workflow converters on the real texture sets of ../shared/assets (docs/evaluation.md)
#   make evaluation-gltf   the glTF conversions and gltf-transform's, rendered as meshes (docs/evaluation.md)
#   make evaluation-hardcases   every spec2metal method on single hard texels, on spheres (docs/evaluation.md)
#   make evaluation-svbrdf   real texture sets as Ward SVBRDFs remapped by every learned method into ggx, beckmann,
#                   as and cycles-principled, on the paper's sphere under the turning Tabac Plant probe
#                   (docs/evaluation-svbrdf.md; 11 min on 2 cores after make)
#   make evaluation-viewers   the same conversions in the viewers people use: Blender Cycles and three.js in
#                   headless Chromium (docs/evaluation.md, "What viewers show"; installs Blender, Chromium, npm pins)
#   make evaluation-clients   matremap export's .mtlx and .usda opened by three.js's MaterialXLoader and USDLoader
#                   in headless Chromium beside matremap's own renders (docs/evaluation-clients.md)
#   make evaluation-translations   MaterialX's translation graphs beside the image-fitted remap, rendered under
#                   both HDR maps (docs/evaluation-translations.md)
#   make evaluation-renderers   node materials of data/blender/node_materials.blend baked to glTF by Blender's
#                   exporter and by matremap, rendered back in Cycles and three.js (docs/evaluation-renderers.md)
#   make dataset    the specular -> metallic training set (build/dataset); make train: data/spec2metal.mlp;
#                   make objectives: which label objective agrees with object SSIM (docs/training.md)
#   make faults     allocation and I/O fault injection (build/faults, ASan + UBSan + LSan): the N-th allocation,
#                   write or rename fails, for every N, over the main commands (scripts/faults.sh; docs/reliability.md);
#                   FAULT_STEP=k tries every k-th N only
#   make deps       installs the Debian packages the project needs (scripts/install-deps.sh)
#   make install PREFIX=/usr/local   tools, static and shared library, public headers, matremap.pc, the network and
#                   the Python package (docs/python.md)

PREFIX   ?= /usr/local
BUILD    ?= build
SAN      ?=
CC       ?= cc
CXX      ?= g++

# Your CFLAGS, CXXFLAGS, CPPFLAGS, LDFLAGS and LDLIBS are used as given (optimisation and debug flags belong there;
# the default is -O2 -g); the project's own flags come from the MR_* variables below and go first.
CFLAGS   ?= -O2 -g
CXXFLAGS ?= -O2 -g
# -Werror where warnings must fail the build: the test builds (make check, make asan; CI runs make check on a clean
# clone, so every object there is built with it) and WERROR=-Werror on any command line. Release builds (make,
# make install) only warn: a newer compiler's new warning must not break a user's build.
ifneq ($(filter check asan,$(MAKECMDGOALS)),)
WERROR   ?= -Werror
endif
WERROR   ?=
WARN     := -Wall -Wextra $(WERROR)

# Dependencies through pkg-config (Debian's packages; scripts/install-deps.sh installs them). A build goal stops
# at once, naming the package, when one is missing; `make deps` and `make clean` do not need them.
PKG_CONFIG ?= pkg-config
NEEDS_DEPS := $(if $(MAKECMDGOALS),$(filter-out deps clean,$(MAKECMDGOALS)),all)
ifneq ($(NEEDS_DEPS),)
missing = $(foreach p,$(1),$(if $(shell $(PKG_CONFIG) --exists $(word 1,$(subst :, ,$(p))) && echo y),,$(p)))
MISSING := $(call missing,nlopt:libnlopt-dev OpenEXR:libopenexr-dev tinygltf:libtinygltf-dev libpng:libpng-dev \
                          libdeflate:libdeflate-dev OpenImageIO:libopenimageio-dev tinyobjloader:libtinyobjloader-dev \
                          expat:libexpat1-dev)
# libsvm ships no pkg-config file: its header stands for the package.
ifeq ($(wildcard /usr/include/libsvm/svm.h),)
MISSING += libsvm:libsvm-dev
endif
ifneq ($(strip $(MISSING)),)
$(error pkg-config cannot find $(foreach p,$(MISSING),$(word 1,$(subst :, ,$(p))) (Debian package \
        $(word 2,$(subst :, ,$(p))))); run scripts/install-deps.sh (or make deps))
endif
endif
DEP_CFLAGS := $(shell $(PKG_CONFIG) --cflags nlopt OpenEXR tinygltf libpng libdeflate tinyobjloader expat \
                2>/dev/null)
# --as-needed keeps only the libraries the objects use: OpenEXR's .pc lists its C++ libraries as well, of which
# the library reads and writes through OpenEXRCore alone (each shared library costs start-up time).
# The C++ libraries (tinygltf, tinyobjloader, libsvm) live in the C++ module (src/cxx_module.c says why): linked
# into the library only when CXX_MODULE=0, as the fault-injection and fuzzing builds do.
CXX_MODULE ?= 1
CXX_DEP_LIBS := $(shell $(PKG_CONFIG) --libs tinygltf tinyobjloader 2>/dev/null) -lsvm
DEP_LIBS   := -Wl,--as-needed $(shell $(PKG_CONFIG) --libs nlopt OpenEXR libpng libdeflate expat 2>/dev/null) \
              $(if $(filter 0,$(CXX_MODULE)),$(CXX_DEP_LIBS)) -lm

MODULE_DIR := $(PREFIX)/lib/matremap
# Where make install puts the Python package: Debian's site directory for PREFIX (PREFIX/lib/python3.X/dist-packages,
# on sys.path for /usr/local), or PYTHON_SITE=... (then on PYTHONPATH).
PYTHON_SITE ?= $(PREFIX)/lib/python$(shell /usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])' \
                                      2>/dev/null)/dist-packages
DATA_DIR   := $(PREFIX)/share/matremap
MR_CPPFLAGS := -D_POSIX_C_SOURCE=200809L -Isrc -I. $(DEP_CFLAGS) -DMR_MODULE_DIR='"$(MODULE_DIR)"' \
               -DMR_DATA_DIR='"$(DATA_DIR)"' -DMR_CXX_MODULE=$(CXX_MODULE)
MR_CFLAGS   := -std=c11 -pedantic $(WARN) $(SAN) -fopenmp
MR_CXXFLAGS := -std=c++17 $(WARN) $(SAN) -fopenmp -Isrc -I. $(shell $(PKG_CONFIG) --cflags OpenImageIO 2>/dev/null)
MR_LDFLAGS  := $(SAN) -fopenmp
ALL_CFLAGS   = $(MR_CPPFLAGS) $(CPPFLAGS) $(MR_CFLAGS) $(CFLAGS)
ALL_CXXFLAGS = $(CPPFLAGS) $(MR_CXXFLAGS) $(CXXFLAGS)
ALL_LDFLAGS  = $(MR_LDFLAGS) $(LDFLAGS)
ALL_LDLIBS   = $(DEP_LIBS) $(LDLIBS)

# OpenImageIO lives in a module loaded on first use (src/io/oiio_module.c says why). It carries its own
# copies of the status and atomic-file code, compiled position-independent with hidden visibility.
MODULE      := $(BUILD)/lib/matremap/libmatremap-oiio.so
MODULE_SRC  := src/io/image_io_oiio.cpp src/status.c src/io/atomic_file.c
MODULE_OBJ  := $(patsubst %,$(BUILD)/pic/%.o,$(basename $(MODULE_SRC)))

# MPI is optional: `matremap sweep` under mpirun loads a module holding every MPI call (src/remap/sweep_mpi.c says
# why), built only where pkg-config knows Open MPI's mpi-c (libopenmpi-dev); MPI=0 leaves it out. Nothing else
# links MPI, so the library, the tool and the tests build and run without it.
MPI         ?= 1
MPI_PC      := $(if $(filter 1,$(MPI)),$(shell $(PKG_CONFIG) --exists mpi-c 2>/dev/null && echo mpi-c))
MPI_MODULE  := $(if $(MPI_PC),$(BUILD)/lib/matremap/libmatremap-mpi.so)
MPI_SRC     := src/remap/sweep_mpi_module.c

LIB_C_SRC   := $(filter-out src/cli/% $(MPI_SRC) src/cxx_module_table.c,$(wildcard src/*.c src/*/*.c)) \
               $(wildcard nn/*.c gltf/*.c)
# The C++ shims (glTF, OBJ): in the C++ module, or in the library itself when CXX_MODULE=0.
CXX_SHIM_SRC := $(filter-out src/io/image_io_oiio.cpp,$(wildcard src/*/*.cpp)) $(wildcard gltf/*.cpp)
LIB_CXX_SRC := $(if $(filter 0,$(CXX_MODULE)),$(CXX_SHIM_SRC))
# The C++ module: the shims, libsvm's table, and its own copies of the library functions they call (status.c's
# message is the module's; the forwarders of src/cxx_module.c carry it over).
CXX_MODULE_LIB := $(if $(filter 0,$(CXX_MODULE)),,$(BUILD)/lib/matremap/libmatremap-cxx.so)
CXX_MODULE_SRC := $(CXX_SHIM_SRC) src/cxx_module_table.c src/status.c src/io/atomic_file.c src/io/input_file.c \
                  gltf/material_defaults.c
CXX_MODULE_OBJ := $(patsubst %,$(BUILD)/pic/%.o,$(basename $(CXX_MODULE_SRC)))
CLI_SRC     := $(wildcard src/cli/*.c)
TEST_SRC    := $(wildcard tests/test_*.c)
BENCH_SRC   := $(wildcard tests/bench_*.c)

LIB_OBJ   := $(LIB_C_SRC:%.c=$(BUILD)/obj/%.o) $(LIB_CXX_SRC:%.cpp=$(BUILD)/obj/%.o)
CLI_OBJ   := $(CLI_SRC:%.c=$(BUILD)/obj/%.o)
LIB       := $(BUILD)/libmatremap.a
SHLIB_SONAME := libmatremap.so.0
SHLIB     := $(BUILD)/lib/libmatremap.so.0.1.0
SHLIB_LINKS := $(BUILD)/lib/$(SHLIB_SONAME) $(BUILD)/lib/libmatremap.so
SHLIB_OBJ := $(LIB_C_SRC:%.c=$(BUILD)/shobj/%.o) $(LIB_CXX_SRC:%.cpp=$(BUILD)/shobj/%.o)
TOOLS     := $(BUILD)/bin/matremap
# spec2metal and metal2spec are matremap under another name (main.c dispatches on the program's name).
TOOL_LINKS := $(BUILD)/bin/spec2metal $(BUILD)/bin/metal2spec
# The network of `spec2metal --method mlp`, where cmd_workflow.c looks for it beside an installed tree
# (PREFIX/bin -> PREFIX/share/matremap); the build tree gets a copy in the same place, so every BUILD finds it.
NETWORK   := $(BUILD)/share/matremap/spec2metal.mlp
TESTS     := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
# Fuzz targets (tests/fuzz/): linked into tests/test_fuzz_inputs for make check, and one libFuzzer binary each
# for make fuzz. They reach the CLI's value parsers too, so they link the CLI's objects except main().
FUZZ_NAMES  := gltf png jpeg exr hdr mlp mrt sweep cli_value obj mtlx
FUZZ_OBJ    := $(patsubst %,$(BUILD)/obj/tests/fuzz/fuzz_%.o,$(FUZZ_NAMES) support)
CLI_LIB_OBJ := $(filter-out $(BUILD)/obj/src/cli/main.o,$(CLI_OBJ))
BENCHES   := $(BENCH_SRC:tests/%.c=$(BUILD)/tests/%)

PUBLIC_HEADERS := src/matremap.h src/mr_core.h src/mr_status.h src/mr_image.h src/brdf/brdf.h src/render/render.h src/render/renderer.h \
                  src/io/image_io.h src/io/obj_load.h src/metrics/metrics.h src/remap/remap.h src/remap/direct.h \
                  src/remap/sweep.h src/workflow/workflow.h src/workflow/dataset.h src/workflow/labels.h \
                  src/workflow/pairs.h src/learn/learned_plots.h src/io/output_plan.h \
                  src/transform/transform.h src/report/report.h nn/mlp.h \
                  src/learn/parametric.h src/learn/svr.h src/learn/sweep_table.h src/learn/learned.h \
                  gltf/mr_gltf.h gltf/mr_gltf_convert.h gltf/mr_gltf_scene.h gltf/mr_gltf_library.h src/doc/doc.h \
                  src/remap/translate.h src/api/api.h

.PHONY: all check asan fuzz fuzz-targets faults demo bench \
        analyses paper evaluation evaluation-gltf evaluation-hardcases evaluation-svbrdf \
        evaluation-viewers evaluation-clients evaluation-translations evaluation-renderer-fits evaluation-renderers dataset train objectives deps install clean tables
# The batched BRDF kernels of src/brdf are plain loops GCC vectorises (brdf_batch.h): -fno-math-errno makes sqrt one
# instruction and -fno-trapping-math lets a branch become a select. Neither changes a value (unlike -ffast-math);
# docs/performance.md, "Vectorised lobes".
$(BUILD)/obj/src/brdf/%.o $(BUILD)/pic/src/brdf/%.o $(BUILD)/shobj/src/brdf/%.o: MR_CFLAGS += -fno-math-errno -fno-trapping-math
# Keep test objects between runs (they are intermediate files of the test binaries).
.SECONDARY:
all: $(LIB) $(TOOLS) $(TOOL_LINKS) $(NETWORK) $(MODULE) $(CXX_MODULE_LIB) $(MPI_MODULE) $(SHLIB_LINKS)

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@

$(BUILD)/pic/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@

# -z defs: every symbol the module needs is resolved at link time. Not in the fuzz build, where clang's sanitizer and
# libFuzzer runtimes live in the executable that loads the module.
MODULE_DEFS ?= -Wl,-z,defs
$(MODULE): $(MODULE_OBJ)
	@mkdir -p $(dir $@)
	$(CXX) -shared $(ALL_LDFLAGS) -Wl,-Bsymbolic $(MODULE_DEFS) $^ $(shell $(PKG_CONFIG) --libs OpenImageIO 2>/dev/null) -o $@

$(CXX_MODULE_LIB): $(CXX_MODULE_OBJ)
	@mkdir -p $(dir $@)
	$(CXX) -shared $(ALL_LDFLAGS) -Wl,-Bsymbolic $(MODULE_DEFS) $^ $(CXX_DEP_LIBS) -o $@

# The MPI module: plain C against Open MPI's headers and library (what mpicc adds, taken from pkg-config, so that
# CC and the sanitizers stay the project's).
$(BUILD)/lib/matremap/libmatremap-mpi.so: $(MPI_SRC)
	@mkdir -p $(dir $@)
	$(CC) -D_POSIX_C_SOURCE=200809L -std=c11 $(WARN) $(SAN) $(CFLAGS) -fPIC -fvisibility=hidden -shared \
	    $(shell $(PKG_CONFIG) --cflags mpi-c 2>/dev/null) $(LDFLAGS) -Wl,-z,defs $< \
	    $(shell $(PKG_CONFIG) --libs mpi-c 2>/dev/null) -o $@

# The shared library (docs/python.md): the library's objects again, position-independent, in their own object
# directory (build/shobj; the static library stays as it is), linked with every dependency (-z defs: nothing left
# unresolved) and exporting only mr_* (src/libmatremap.map). It finds its modules in matremap/ beside itself and its
# data in ../share/matremap (src/data_dir.c), so build/lib works as PREFIX/lib does.
$(BUILD)/shobj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -fPIC -MMD -MP -c $< -o $@

$(BUILD)/shobj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) -fPIC -MMD -MP -c $< -o $@

$(SHLIB): $(SHLIB_OBJ) src/libmatremap.map
	@mkdir -p $(dir $@)
	$(LINK) -shared $(ALL_LDFLAGS) -Wl,-soname,$(SHLIB_SONAME) -Wl,--version-script=src/libmatremap.map \
	    -Wl,-z,defs $(SHLIB_OBJ) $(ALL_LDLIBS) -o $@

$(BUILD)/lib/$(SHLIB_SONAME) $(BUILD)/lib/libmatremap.so: $(SHLIB)
	ln -sfn $(notdir $(SHLIB)) $@

# The module and data directories are compiled into oiio_module.o and cmd_workflow.o (the network); this stamp
# changes (and so rebuilds them) when PREFIX does, e.g. for `make install PREFIX=...` after a plain `make`.
$(BUILD)/module_dir.stamp: FORCE
	@mkdir -p $(dir $@)
	@echo '$(MODULE_DIR) $(DATA_DIR)' | cmp -s - $@ || echo '$(MODULE_DIR) $(DATA_DIR)' > $@
$(BUILD)/obj/src/io/oiio_module.o $(BUILD)/obj/src/cli/cmd_workflow.o $(BUILD)/obj/src/remap/sweep_mpi.o \
    $(BUILD)/obj/src/cxx_module.o $(BUILD)/shobj/src/cxx_module.o: $(BUILD)/module_dir.stamp
$(BUILD)/shobj/src/io/oiio_module.o $(BUILD)/shobj/src/remap/sweep_mpi.o $(BUILD)/shobj/src/data_dir.o \
    $(BUILD)/obj/src/data_dir.o: $(BUILD)/module_dir.stamp
.PHONY: FORCE
FORCE:

$(LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

# Programs link with the C++ driver only when the library holds C++ objects (the glTF shim).
LINK := $(if $(strip $(LIB_CXX_SRC)),$(CXX),$(CC))

# FAULTS=1 (make faults): the tool is linked with the fault injector, whose wrappers GNU ld's --wrap puts between
# the project's own objects and these functions (tests/fault_inject.c says why and how); the one symbol exported
# lets fault_inject_new.cpp recognise its caller (nlohmann/json's destructor) with dladdr.
FAULT_OBJ  := $(if $(FAULTS),$(BUILD)/obj/tests/fault_inject.o $(BUILD)/obj/tests/fault_inject_new.o)
FAULT_WRAP := main malloc calloc realloc strdup _Znwm _Znam _ZnwmRKSt9nothrow_t _ZnamRKSt9nothrow_t \
              fopen open write fwrite fputs fputc putc fprintf vfprintf fflush fclose fsync ftruncate rename mkdir
ifneq ($(FAULTS),)
FAULT_LDFLAGS := -Wl,--export-dynamic-symbol='*json_value7destroy*' $(foreach f,$(FAULT_WRAP),-Wl,--wrap=$(f))
endif

$(BUILD)/bin/matremap: $(CLI_OBJ) $(LIB) $(FAULT_OBJ)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) $(FAULT_LDFLAGS) $(CLI_OBJ) $(FAULT_OBJ) $(LIB) $(ALL_LDLIBS) -o $@

$(TOOL_LINKS): $(BUILD)/bin/matremap
	ln -sfn matremap $@

$(NETWORK): data/spec2metal.mlp
	@mkdir -p $(dir $@)
	cp $< $@

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) $< $(LIB) $(ALL_LDLIBS) -o $@

# test_svr checks the SVR trainer's answers against libsvm's own predictions: it calls libsvm itself.
$(BUILD)/tests/test_svr: ALL_LDLIBS += $(if $(filter 0,$(CXX_MODULE)),,-lsvm)

$(BUILD)/tests/test_fuzz_inputs: $(BUILD)/obj/tests/test_fuzz_inputs.o $(FUZZ_OBJ) $(CLI_LIB_OBJ) $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) $^ $(ALL_LDLIBS) -o $@

# The thread counter tests/threads_cli.sh preloads (tests/thread_count.c): a test instrument, so built without
# the sanitizers, in every BUILD.
THREAD_COUNTER := $(BUILD)/tests/libthread_count.so
$(THREAD_COUNTER): tests/thread_count.c
	@mkdir -p $(dir $@)
	$(CC) -std=c11 -pedantic $(WARN) -O1 -fPIC -shared $< -ldl -o $@

# headers_cpp.o only has to compile: every public header must be valid C++ as well as C.
check: all $(TESTS) $(THREAD_COUNTER) $(BUILD)/obj/tests/headers_cpp.o
	scripts/run-tests.sh $(BUILD)

asan:
	$(MAKE) BUILD=build/asan CFLAGS="-O1 -g -fno-omit-frame-pointer" CXXFLAGS="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" check

# make fuzz: every libFuzzer target (tests/fuzz/, docs/reliability.md) built with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer into build/fuzz, then run one after another for FUZZ_SECONDS each (and at most
# FUZZ_RUNS executions each, when given); FUZZ_TARGETS picks some (default all). Findings go to
# build/fuzz/findings, every run's figures to build/fuzz/runs.tsv.
FUZZ_SECONDS ?= 60
FUZZ_RUNS    ?= 0
FUZZ_TARGETS ?=
FUZZ_FLAGS   := -O1 -g -fno-omit-frame-pointer
fuzz: all
	$(MAKE) BUILD=build/fuzz CC=clang CXX=clang++ CFLAGS="$(FUZZ_FLAGS)" CXXFLAGS="$(FUZZ_FLAGS)" MODULE_DEFS= CXX_MODULE=0 \
	    SAN="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" fuzz-targets
	scripts/fuzz.sh $(BUILD) build/fuzz $(FUZZ_SECONDS) $(FUZZ_RUNS) $(FUZZ_TARGETS)

fuzz-targets: $(FUZZ_NAMES:%=$(BUILD)/bin/fuzz_%) $(MODULE) $(CXX_MODULE_LIB)

$(BUILD)/obj/tests/fuzz/libfuzzer_%.o: tests/fuzz/fuzz_%.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -DMR_FUZZ_LIBFUZZER -MMD -MP -c $< -o $@

$(BUILD)/bin/fuzz_%: $(BUILD)/obj/tests/fuzz/libfuzzer_%.o $(BUILD)/obj/tests/fuzz/fuzz_support.o $(CLI_LIB_OBJ) $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) -fsanitize=fuzzer $^ $(ALL_LDLIBS) -o $@

# The fault build is the ASan + UBSan build of make asan with the injector linked in; LeakSanitizer is on (ASan's
# default on Linux). FAULT_STEP=k: every k-th N only (a quick pass), FAULT_ONLY=NAME: one command of the driver.
FAULT_STEP ?= 1
FAULT_ONLY ?=
faults:
	$(MAKE) BUILD=build/faults FAULTS=1 CXX_MODULE=0 CFLAGS="-O1 -g -fno-omit-frame-pointer" \
	    CXXFLAGS="-O1 -g -fno-omit-frame-pointer" SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all
	scripts/faults.sh build/faults $(FAULT_STEP) $(FAULT_ONLY)

demo: all
	scripts/demo.sh $(BUILD)

# BENCH_ARGS: e.g. "--only report-accuracy" runs one section of scripts/bench.sh (the whole run takes long).
BENCH_ARGS ?=
bench: all $(BENCHES)
	scripts/bench.sh $(BUILD) $(BENCH_ARGS)

analyses: all
	scripts/analyses.sh $(BUILD)

paper: all
	scripts/paper-appendix.sh $(BUILD)

evaluation: all
	scripts/evaluate-workflow.sh $(BUILD)

evaluation-gltf: all
	scripts/evaluate-gltf.sh $(BUILD)

evaluation-hardcases: all
	scripts/evaluate-hardcases.sh $(BUILD)

evaluation-svbrdf: all
	scripts/evaluate-svbrdf.sh $(BUILD)

# object_metrics: SSIM and luminance over a render's object pixels (its alpha), from mr_ssim's map.
OBJECT_METRICS := $(BUILD)/tools/object_metrics
$(OBJECT_METRICS): $(BUILD)/obj/scripts/viewers/object_metrics.o $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) $< $(LIB) $(ALL_LDLIBS) -o $@

evaluation-viewers: all $(OBJECT_METRICS)
	scripts/evaluate-viewers.sh $(BUILD)

# doc_write: one uniform material written by the library's document writer (a coat, a metal's specular_color).
DOC_WRITE := $(BUILD)/tools/doc_write
$(DOC_WRITE): $(BUILD)/obj/scripts/viewers/doc_write.o $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(ALL_LDFLAGS) $< $(LIB) $(ALL_LDLIBS) -o $@

evaluation-clients: all $(OBJECT_METRICS) $(DOC_WRITE)
	scripts/evaluate-clients.sh $(BUILD)

# MaterialX's translation graphs beside the image-fitted remap (docs/evaluation-translations.md; ~5 min on 2 cores).
evaluation-translations: all
	scripts/evaluate-translations.sh $(BUILD)

# Fits through real renderers (Blender, three.js) beside fits through the built-in model, Cycles' noise floor, a
# sweep through Blender on MPI ranks: tables for docs/performance.md (docs/renderers.md).
evaluation-renderer-fits: all
	scripts/evaluate-renderer-fits.sh $(BUILD)

# Node materials baked to glTF: Blender's exporter vs matremap, rendered back (docs/evaluation-renderers.md; ~1 min).
evaluation-renderers: all
	scripts/evaluate-renderers.sh $(BUILD)

# The specular -> metallic dataset (image-objective labels, a few minutes on 2 cores) and the network trained on
# it (docs/training.md). `make train` reproduces data/spec2metal.mlp bit for bit.
DATASET := $(BUILD)/dataset
dataset: all
	scripts/dataset.sh $(BUILD) $(DATASET)

train: dataset
	@mkdir -p docs/training
	$(BUILD)/bin/matremap train $(DATASET)/pairs.csv --seed 1 --form residual \
	    -o data/spec2metal.mlp --loss-curve docs/training/spec2metal_loss \
	    --test $(DATASET)/test-pairs.csv | tee docs/training/spec2metal.txt

# Which label objective agrees with object SSIM under held-out lights (docs/training.md, "Objectives").
objectives: all
	scripts/objectives.sh $(BUILD)

deps:
	scripts/install-deps.sh

install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/matremap
	install -m 755 $(TOOLS) $(DESTDIR)$(PREFIX)/bin/
	for l in $(notdir $(TOOL_LINKS)); do ln -sfn matremap $(DESTDIR)$(PREFIX)/bin/$$l; done
	install -d $(DESTDIR)$(PREFIX)/share/matremap
	install -m 644 data/spec2metal.mlp $(DESTDIR)$(PREFIX)/share/matremap/
	install -d $(DESTDIR)$(PREFIX)/share/matremap/renderers/three
	install -m 644 data/renderers/blender_server.py data/renderers/blender_scene.py \
	    $(DESTDIR)$(PREFIX)/share/matremap/renderers/
	install -m 644 data/renderers/three/*.mjs data/renderers/three/*.js data/renderers/three/package*.json \
	    $(DESTDIR)$(PREFIX)/share/matremap/renderers/three/
	# three.js's npm packages go along when scripts/install-deps.sh installed them; else `npm ci` there later
	if [ -d data/renderers/three/node_modules ]; then \
	    cp -r data/renderers/three/node_modules $(DESTDIR)$(PREFIX)/share/matremap/renderers/three/; fi
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SHLIB) $(DESTDIR)$(PREFIX)/lib/
	ln -sfn $(notdir $(SHLIB)) $(DESTDIR)$(PREFIX)/lib/$(SHLIB_SONAME)
	ln -sfn $(notdir $(SHLIB)) $(DESTDIR)$(PREFIX)/lib/libmatremap.so
	# The Python package (docs/python.md), told where the library is by _config.py
	install -d $(DESTDIR)$(PYTHON_SITE)/matremap
	install -m 644 python/matremap/__init__.py python/matremap/__main__.py python/matremap/_native.py \
	    $(DESTDIR)$(PYTHON_SITE)/matremap/
	printf '"""Written by make install."""\nLIBDIR = "%s"\n' '$(PREFIX)/lib' > $(DESTDIR)$(PYTHON_SITE)/matremap/_config.py
	install -d $(DESTDIR)$(MODULE_DIR)
	install -m 755 $(MODULE) $(CXX_MODULE_LIB) $(MPI_MODULE) $(DESTDIR)$(MODULE_DIR)/
	for h in $(PUBLIC_HEADERS); do \
	    d=$(DESTDIR)$(PREFIX)/include/matremap/$$(dirname $${h#src/}); install -d $$d; install -m 644 $$h $$d/; done
	sed -e 's|@PREFIX@|$(PREFIX)|' -e "s|@VERSION@|$$(sed -n 's/^#define MR_VERSION_STRING \"\(.*\)\"/\1/p' src/mr_core.h)|" \
	    -e 's|@CXX_REQUIRES@|$(if $(filter 0,$(CXX_MODULE)), tinygltf tinyobjloader)|' \
	    -e 's|@CXX_LIBS@|$(if $(filter 0,$(CXX_MODULE)), -lstdc++ -lsvm)|' \
	    scripts/matremap.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/matremap.pc

clean:
	rm -rf build

# The GGX directional-albedo tables the layered BRDF models interpolate (src/brdf/layering.c), computed from the
# library's own lobe by scripts/gen-ggx-albedo.c (a minute or two). The header is committed, so `all` does not run
# this; tests/ggx_albedo_table.sh checks a sample of its entries against the same program.
tables:
	@mkdir -p $(BUILD)
	$(CC) -std=c11 -O2 $(WARN) -Isrc scripts/gen-ggx-albedo.c -lm -o $(BUILD)/gen-ggx-albedo
	$(BUILD)/gen-ggx-albedo > src/brdf/ggx_albedo_tables.h.tmp
	mv src/brdf/ggx_albedo_tables.h.tmp src/brdf/ggx_albedo_tables.h

-include $(shell find $(BUILD)/obj $(BUILD)/pic $(BUILD)/shobj -name '*.d' 2>/dev/null)

# The Blender add-on (docs/blender-addon.md): blender/matremap_addon/ zipped with the Python package (python/matremap,
# or ADDON_PY=DIR) bundled in its _vendor/ folder and, as the last place it looks for libmatremap.so.0, this build
# tree's library path (_build.py). Install the zip in Blender: Preferences > Add-ons > Install.
ADDON_ZIP := $(BUILD)/matremap_blender_addon.zip
ADDON_PY  ?= python/matremap
all: $(ADDON_ZIP)
$(ADDON_ZIP): $(wildcard blender/matremap_addon/*.py) $(wildcard $(ADDON_PY)/*.py)
	rm -rf $(BUILD)/blender-addon && mkdir -p $(BUILD)/blender-addon/matremap_addon/_vendor
	cp blender/matremap_addon/*.py $(BUILD)/blender-addon/matremap_addon/
	if [ -d $(ADDON_PY) ]; then cp -r $(ADDON_PY) $(BUILD)/blender-addon/matremap_addon/_vendor/matremap; \
	    find $(BUILD)/blender-addon -name __pycache__ -prune -exec rm -rf {} +; fi
	echo 'LIBRARY = "$(abspath $(BUILD))/lib/libmatremap.so.0"' > $(BUILD)/blender-addon/matremap_addon/_build.py
	cd $(BUILD)/blender-addon && python3 -m zipfile -c $(abspath $@).tmp matremap_addon
	mv $@.tmp $@
