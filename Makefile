# matremap — build, test, demo, benchmark and install. See README.md.
#
#   make            library (build/libmatremap.a) and tools (build/bin/)
#   make check      the test suite (every tests/test_*.c binary and tests/*.sh script)
#   make asan       the test suite built with AddressSanitizer + UndefinedBehaviorSanitizer
#   make demo       renders and compares the demo materials of data/ into out/demo
#   make bench      benchmarks (prints figures, asserts nothing; see docs/performance.md); one section:
#                   make bench BENCH_ARGS="--only report-accuracy"
#   make analyses   the paper's stability analyses (docs/analyses.md)
#   make evaluation the workflow converters on the real texture sets of ../shared/assets (docs/evaluation.md)
#   make evaluation-gltf   the glTF conversions and gltf-transform's, rendered as meshes (docs/evaluation.md)
#   make evaluation-hardcases   every spec2metal method on single hard texels, on spheres (docs/evaluation.md)
#   make evaluation-viewers   the same conversions in the viewers people use: Blender Cycles and three.js in
#                   headless Chromium (docs/evaluation.md, "What viewers show"; installs Blender, Chromium, npm pins)
#   make dataset    the specular -> metallic training set (build/dataset); make train: data/spec2metal.mlp;
#                   make objectives: which label objective agrees with object SSIM (docs/training.md)
#   make deps       installs the Debian packages the project needs (scripts/install-deps.sh)
#   make install PREFIX=/usr/local   tools, static library, public headers, matremap.pc and the network

PREFIX   ?= /usr/local
BUILD    ?= build
OPT      ?= -O2 -g
SAN      ?=
CC       ?= cc
CXX      ?= g++

WARN      := -Wall -Wextra -Werror
MODULE_DIR := $(PREFIX)/lib/matremap
CFLAGS    := -std=c11 -pedantic $(WARN) $(OPT) $(SAN) -fopenmp -D_POSIX_C_SOURCE=200809L -Isrc -I. -I/usr/include/OpenEXR \
             -DMR_MODULE_DIR='"$(MODULE_DIR)"'
CXXFLAGS  := -std=c++17 $(WARN) $(OPT) $(SAN) -fopenmp -Isrc -I. $(shell pkg-config --cflags OpenImageIO 2>/dev/null)
LDFLAGS   := $(SAN) -fopenmp
# -ltinygltf: the glTF shim (gltf/*.cpp) links Debian's compiled tinygltf.
LDLIBS    := $(shell pkg-config --libs nlopt 2>/dev/null) -lOpenEXRCore-3_1 -ltinygltf -lm

# OpenImageIO lives in a module loaded on first use (src/io/oiio_module.c says why). It carries its own
# copies of the status and atomic-file code, compiled position-independent with hidden visibility.
MODULE      := $(BUILD)/lib/matremap/libmatremap-oiio.so
MODULE_SRC  := src/io/image_io_oiio.cpp src/status.c src/io/atomic_file.c
MODULE_OBJ  := $(patsubst %,$(BUILD)/pic/%.o,$(basename $(MODULE_SRC)))

LIB_C_SRC   := $(filter-out src/cli/%,$(wildcard src/*.c src/*/*.c)) $(wildcard nn/*.c)
LIB_CXX_SRC := $(filter-out src/io/image_io_oiio.cpp,$(wildcard src/*/*.cpp)) $(wildcard gltf/*.cpp)
CLI_SRC     := $(wildcard src/cli/*.c)
TEST_SRC    := $(wildcard tests/test_*.c)
BENCH_SRC   := $(wildcard tests/bench_*.c)

LIB_OBJ   := $(LIB_C_SRC:%.c=$(BUILD)/obj/%.o) $(LIB_CXX_SRC:%.cpp=$(BUILD)/obj/%.o)
CLI_OBJ   := $(CLI_SRC:%.c=$(BUILD)/obj/%.o)
LIB       := $(BUILD)/libmatremap.a
TOOLS     := $(BUILD)/bin/matremap
# spec2metal and metal2spec are matremap under another name (main.c dispatches on the program's name).
TOOL_LINKS := $(BUILD)/bin/spec2metal $(BUILD)/bin/metal2spec
# The network of `spec2metal --method mlp`, where cmd_workflow.c looks for it beside an installed tree
# (PREFIX/bin -> PREFIX/share/matremap); the build tree gets a copy in the same place, so every BUILD finds it.
NETWORK   := $(BUILD)/share/matremap/spec2metal.mlp
TESTS     := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
BENCHES   := $(BENCH_SRC:tests/%.c=$(BUILD)/tests/%)

PUBLIC_HEADERS := src/matremap.h src/mr_status.h src/mr_image.h src/brdf/brdf.h src/render/render.h \
                  src/io/image_io.h src/metrics/metrics.h src/remap/remap.h src/workflow/workflow.h \
                  src/workflow/dataset.h src/workflow/labels.h src/report/report.h nn/mlp.h gltf/mr_gltf.h

.PHONY: all check asan demo bench analyses evaluation evaluation-gltf evaluation-hardcases evaluation-viewers dataset \
        train objectives deps install clean
# Keep test objects between runs (they are intermediate files of the test binaries).
.SECONDARY:
all: $(LIB) $(TOOLS) $(TOOL_LINKS) $(NETWORK) $(MODULE)

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@

$(BUILD)/pic/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@

$(MODULE): $(MODULE_OBJ)
	@mkdir -p $(dir $@)
	$(CXX) -shared $(LDFLAGS) -Wl,-Bsymbolic -Wl,-z,defs $^ $(shell pkg-config --libs OpenImageIO 2>/dev/null) -o $@

# The module directory is compiled into oiio_module.o; this stamp changes (and so rebuilds it) when PREFIX does,
# e.g. for `make install PREFIX=...` after a plain `make`.
$(BUILD)/module_dir.stamp: FORCE
	@mkdir -p $(dir $@)
	@echo '$(MODULE_DIR)' | cmp -s - $@ || echo '$(MODULE_DIR)' > $@
$(BUILD)/obj/src/io/oiio_module.o: $(BUILD)/module_dir.stamp
.PHONY: FORCE
FORCE:

$(LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

# Programs link with the C++ driver only when the library holds C++ objects (the glTF shim).
LINK := $(if $(strip $(LIB_CXX_SRC)),$(CXX),$(CC))

$(BUILD)/bin/matremap: $(CLI_OBJ) $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(LDFLAGS) $(CLI_OBJ) $(LIB) $(LDLIBS) -o $@

$(TOOL_LINKS): $(BUILD)/bin/matremap
	ln -sfn matremap $@

$(NETWORK): data/spec2metal.mlp
	@mkdir -p $(dir $@)
	cp $< $@

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(LDFLAGS) $< $(LIB) $(LDLIBS) -o $@

# headers_cpp.o only has to compile: every public header must be valid C++ as well as C.
check: all $(TESTS) $(BUILD)/obj/tests/headers_cpp.o
	scripts/run-tests.sh $(BUILD)

asan:
	$(MAKE) BUILD=build/asan OPT="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" check

demo: all
	scripts/demo.sh $(BUILD)

# BENCH_ARGS: e.g. "--only report-accuracy" runs one section of scripts/bench.sh (the whole run takes long).
BENCH_ARGS ?=
bench: all $(BENCHES)
	scripts/bench.sh $(BUILD) $(BENCH_ARGS)

analyses: all
	scripts/analyses.sh $(BUILD)

evaluation: all
	scripts/evaluate-workflow.sh $(BUILD)

evaluation-gltf: all
	scripts/evaluate-gltf.sh $(BUILD)

evaluation-hardcases: all
	scripts/evaluate-hardcases.sh $(BUILD)

# object_metrics: SSIM and luminance over a render's object pixels (its alpha), from mr_ssim's map.
OBJECT_METRICS := $(BUILD)/tools/object_metrics
$(OBJECT_METRICS): $(BUILD)/obj/scripts/viewers/object_metrics.o $(LIB)
	@mkdir -p $(dir $@)
	$(LINK) $(LDFLAGS) $< $(LIB) $(LDLIBS) -o $@

evaluation-viewers: all $(OBJECT_METRICS)
	scripts/evaluate-viewers.sh $(BUILD)

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
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/
	install -d $(DESTDIR)$(MODULE_DIR)
	install -m 755 $(MODULE) $(DESTDIR)$(MODULE_DIR)/
	for h in $(PUBLIC_HEADERS); do \
	    d=$(DESTDIR)$(PREFIX)/include/matremap/$$(dirname $${h#src/}); install -d $$d; install -m 644 $$h $$d/; done
	sed -e 's|@PREFIX@|$(PREFIX)|' -e "s|@VERSION@|$$(sed -n 's/^#define MR_VERSION_STRING \"\(.*\)\"/\1/p' src/matremap.h)|" \
	    scripts/matremap.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/matremap.pc

clean:
	rm -rf build

-include $(shell find $(BUILD)/obj $(BUILD)/pic -name '*.d' 2>/dev/null)
