# Detailed-surface graphics headers: build, demo, tests, benches.
#   make demo      build the examples and render the default scenes into out/ (as root: glmark2-data first)
#   make gallery   make demo, then its pictures made small into docs/ (the README's gallery)
#   make test      install missing test dependencies (as root), build and run every test
#   make sanitize  the same tests built with AddressSanitizer + UndefinedBehaviorSanitizer
#   make fuzz      clang libFuzzer targets, each run for FUZZ_TIME seconds (default 60)
#   make bench     install the peers, run the side-by-side benchmarks, write bench/RESULTS.md
#   make clean
# Works with CC=gcc and CC=clang (CXX follows CC unless given). Everything is built under build/.

B        ?= build
OUT      ?= out
ifeq ($(origin CXX),default)
  ifneq ($(findstring clang,$(CC)),)
    CXX = clang++
  else
    CXX = g++
  endif
endif
WARN     = -Wall -Wextra -pedantic -Werror
OPT      ?= -O2 -g
XFLAGS   ?=
INC      = -I. -Iexamples -Itests -Ibench
CFLAGS_ALL   = -std=c99 $(WARN) $(OPT) $(XFLAGS) $(INC)
CXXFLAGS_ALL = -std=c++17 $(WARN) $(OPT) $(XFLAGS) $(INC)
SANFLAGS = -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
FUZZ_TIME ?= 60

# The library headers that exist so far, and the examples' shared headers.
LIBHEADERS = $(wildcard dispmesh.h erosion.h texel.h subdiv4.h deform.h)
EXHEADERS  = $(wildcard examples/*.h)
HEADERS    = $(LIBHEADERS) $(EXHEADERS)
ALLDEPS    = $(HEADERS) $(wildcard tests/*.h tests/*.hpp bench/*.h) Makefile

HAVE_OPENMESH := $(wildcard /usr/include/OpenMesh/Core/IO/MeshIO.hh)
HAVE_EMBREE   := $(wildcard /usr/include/embree3/rtcore.h)
HAVE_CXX      := $(shell command -v $(CXX) 2>/dev/null)
HAVE_OSMESA   := $(wildcard /usr/include/GL/osmesa.h)
HAVE_MESHOPT  := $(wildcard /usr/include/meshoptimizer.h)
HAVE_CHOLMOD  := $(wildcard /usr/include/suitesparse/cholmod.h)
HAVE_EIGEN    := $(wildcard /usr/include/eigen3/Eigen/Sparse)
HAVE_ASSIMP   := $(wildcard /usr/include/assimp/Importer.hpp)
HAVE_TINYOBJ  := $(wildcard /usr/include/tiny_obj_loader.h)

EXAMPLES   = $(B)/meshconv $(B)/render_mesh $(B)/terrain $(B)/dispmesh
C_TESTS    = $(B)/test_meshio $(B)/test_sphere $(B)/test_render $(B)/test_dispmesh_bvh $(B)/test_dispmesh_simplify \
             $(B)/test_subdiv4 $(B)/test_deform_chol $(B)/test_dispmesh_param $(B)/test_dispmesh_shell $(B)/test_dispmesh_digest \
             $(B)/test_dispmesh_recon $(B)/test_dispmesh_orient
ifeq ($(shell uname -m),x86_64)
  C_TESTS += $(B)/test_dispmesh_bvh_sse2 $(B)/test_dispmesh_bvh_avx2 $(B)/test_dispmesh_digest_avx2
endif
FUZZ_FMTS  = obj off ply stl
FUZZ_PLAIN = $(FUZZ_FMTS:%=$(B)/fuzz_%)
REF_TESTS  = $(if $(and $(HAVE_CXX),$(HAVE_OPENMESH)),$(B)/ref_openmesh $(B)/ref_openmesh_butterfly) \
             $(if $(and $(HAVE_CXX),$(HAVE_EMBREE)),$(B)/ref_embree $(B)/ref_embree_bvh $(B)/ref_dispmesh_base) \
             $(if $(and $(HAVE_CXX),$(HAVE_OPENMESH),$(HAVE_EMBREE)),$(B)/ref_openmesh_simplify) \
             $(if $(and $(HAVE_CXX),$(HAVE_EMBREE),$(HAVE_MESHOPT)),$(B)/ref_dispmesh_bake)
BENCHES    = $(if $(and $(HAVE_CXX),$(HAVE_OPENMESH),$(HAVE_ASSIMP),$(HAVE_TINYOBJ)),$(B)/bench_meshio) \
             $(if $(and $(HAVE_CXX),$(HAVE_OSMESA)),$(B)/bench_raster) \
             $(if $(and $(HAVE_CXX),$(HAVE_EMBREE),$(HAVE_MESHOPT)),$(B)/bench_bvh) \
             $(if $(and $(HAVE_CXX),$(HAVE_OPENMESH)),$(B)/bench_subdiv4) \
             $(if $(and $(HAVE_CXX),$(HAVE_EMBREE),$(HAVE_MESHOPT),$(HAVE_OPENMESH)),$(B)/bench_simplify) \
             $(if $(and $(HAVE_CXX),$(HAVE_CHOLMOD),$(HAVE_EIGEN)),$(B)/bench_chol) \
             $(if $(and $(HAVE_CXX),$(HAVE_MESHOPT)),$(B)/bench_dispmesh)
TOOLS      = $(B)/gen_sphere

# Each header's own targets (examples, tests, benches) in a fragment of its own: mk/<header>.mk appends to
# EXAMPLES, C_TESTS, REF_TESTS, BENCHES and TOOLS and may add rules.
include $(sort $(wildcard mk/*.mk))

.PHONY: all demo gallery test test-build sanitize fuzz fuzz-build bench bench-build clean
.DELETE_ON_ERROR:

all: $(EXAMPLES) $(TOOLS) $(C_TESTS) $(FUZZ_PLAIN) $(REF_TESTS) $(BENCHES)

# ---- examples -------------------------------------------------------------------------------------
$(EXAMPLES): $(B)/%: examples/%.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< -o $@ -lm

$(B)/gen_sphere: bench/gen_sphere.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< -o $@ -lm

# As root, glmark2-data (the bunny and the asteroid height map) is installed first when missing, as
# `make test` installs its packages; otherwise the bunny scenes are skipped and named.
demo: $(EXAMPLES) $(TOOLS)
	@if [ "$$(id -u)" = 0 ] && command -v dpkg-query >/dev/null 2>&1 && \
	    ! dpkg-query -W -f='$${Status}' glmark2-data 2>/dev/null | grep -q 'install ok installed'; then \
	  echo "demo: installing glmark2-data" >&2; \
	  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends glmark2-data >/dev/null 2>&1 || \
	  { apt-get update -q >/dev/null 2>&1; DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends glmark2-data >&2; } || \
	  echo "demo: could not install glmark2-data: the bunny scenes are skipped" >&2; \
	fi
	@mkdir -p $(OUT)
	@sh examples/demo.sh $(B) $(OUT)

# The README's gallery: `make demo`, then each of its pictures made small (docs/thumbnail.c) as docs/NAME.png.
gallery: demo $(B)/thumbnail
	@sh docs/gallery.sh $(B) $(OUT)

# generated meshes for tests/dispmesh_meshes.sh
$(B)/gen_shapes: tests/gen_shapes.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< -o $@ -lm

$(B)/thumbnail: docs/thumbnail.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< -o $@ -lm

# ---- tests ----------------------------------------------------------------------------------------
$(B)/test_%: tests/test_%.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< -o $@ -lm

# dispmesh.h's SIMD paths, for tests/simd_same.sh (x86-64 only)
$(B)/test_dispmesh_bvh_sse2: tests/test_dispmesh_bvh.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DDM_USE_SSE2 $< -o $@ -lm
$(B)/test_dispmesh_bvh_avx2: tests/test_dispmesh_bvh.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DDM_USE_AVX2 -mavx2 $< -o $@ -lm
$(B)/test_dispmesh_digest_avx2: tests/test_dispmesh_digest.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DDM_USE_AVX2 -mavx2 $< -o $@ -lm

$(B)/fuzz_%: tests/fuzz_%.c tests/fuzz_main.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) $< tests/fuzz_main.c -o $@ -lm

$(B)/ref_openmesh: tests/ref_openmesh.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lOpenMeshCore -lm

$(B)/ref_openmesh_butterfly: tests/ref_openmesh_butterfly.cpp tests/butterfly_compare.hpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lOpenMeshCore -lm

$(B)/ref_embree $(B)/ref_embree_bvh $(B)/ref_dispmesh_base: $(B)/%: tests/%.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lembree3 -lm

$(B)/ref_openmesh_simplify: tests/ref_openmesh_simplify.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lOpenMeshTools -lOpenMeshCore -lembree3 -lm
$(B)/ref_dispmesh_bake: tests/ref_dispmesh_bake.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lembree3 -lmeshoptimizer -lm

# Dependencies are installed first; the build is a separate make so that it sees what was installed,
# on every core (JOBS; the tests themselves run one at a time).
JOBS ?= $(shell getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)
test:
	@tests/deps.sh test
	@$(MAKE) --no-print-directory -j$(JOBS) test-build
	@HEADERS="$(HEADERS)" tests/run.sh $(B)

test-build: $(C_TESTS) $(FUZZ_PLAIN) $(REF_TESTS)

sanitize:
	@tests/deps.sh test
	@$(MAKE) --no-print-directory -j$(JOBS) test-build B=$(B)/san OPT="-O1 -g" XFLAGS="$(SANFLAGS)"
	@ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 tests/run.sh $(B)/san sanitize

# ---- fuzzing (clang + libFuzzer) ------------------------------------------------------------------
FUZZ_LF = $(FUZZ_FMTS:%=$(B)/fuzz/fuzz_%)
$(B)/fuzz/fuzz_%: tests/fuzz_%.c $(ALLDEPS)
	@mkdir -p $(B)/fuzz
	clang -std=c99 -g -O1 $(INC) -fsanitize=fuzzer,address,undefined $< -o $@ -lm

fuzz-build: $(FUZZ_LF)

fuzz: fuzz-build
	@for f in $(FUZZ_FMTS); do \
	  mkdir -p $(B)/fuzz/corpus_$$f && cp -n tests/fuzz/corpus/$$f/* $(B)/fuzz/corpus_$$f/ 2>/dev/null; \
	  echo "fuzz_$$f: $(FUZZ_TIME) s" >&2; \
	  $(B)/fuzz/fuzz_$$f -max_total_time=$(FUZZ_TIME) -rss_limit_mb=2048 -print_final_stats=1 \
	     -artifact_prefix=$(B)/fuzz/crash_$$f- $(B)/fuzz/corpus_$$f 2>$(B)/fuzz/fuzz_$$f.log || { tail -n 30 $(B)/fuzz/fuzz_$$f.log; exit 1; }; \
	  echo "RESULT fuzz_$$f $$(grep -E 'stat::number_of_executed_units' $(B)/fuzz/fuzz_$$f.log | awk '{print "executions=" $$2}') seconds=$(FUZZ_TIME)"; \
	done

# ---- benchmarks -----------------------------------------------------------------------------------
# Each bench names the peer libraries it links in BENCH_LIBS_<name>.
BENCH_LIBS_meshio = -lOpenMeshCore -lassimp -ltinyobjloader
BENCH_LIBS_raster = -lOSMesa
BENCH_LIBS_bvh    = -lembree3 -lmeshoptimizer
BENCH_LIBS_subdiv4 = -lOpenMeshCore
BENCH_LIBS_dispmesh = -lmeshoptimizer
# and the flags it is built with: dispmesh.h's SIMD path as its docs recommend for this machine (Embree
# picks its best instruction set at run time)
HAVE_AVX2 := $(shell grep -qw avx2 /proc/cpuinfo 2>/dev/null && echo 1)
BENCH_FLAGS_bvh = $(if $(HAVE_AVX2),-DDM_USE_AVX2 -mavx2,$(if $(filter x86_64,$(shell uname -m)),-DDM_USE_SSE2))
BENCH_FLAGS_dispmesh = $(BENCH_FLAGS_bvh)
BENCH_LIBS_simplify = -lOpenMeshTools -lOpenMeshCore -lembree3 -lmeshoptimizer
# Every bench, both sides, is a release build: the peers' header-only code (OpenMesh, Eigen, CGAL)
# compiles into the bench, and with its asserts on it runs up to twice as slow.
BENCH_OPT = -DNDEBUG
# CHOLMOD and Eigen headers are system headers (their warnings are not ours)
BENCH_FLAGS_chol = -isystem /usr/include/suitesparse -isystem /usr/include/eigen3
BENCH_LIBS_chol = -lcholmod -lsuitesparseconfig -ldl

$(B)/bench_%: bench/bench_%.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $(BENCH_OPT) $(BENCH_FLAGS_$*) -DBENCH_FLAGS='"$(CXX) $(CXXFLAGS_ALL) $(BENCH_OPT) $(BENCH_FLAGS_$*)"' $< -o $@ $(BENCH_LIBS_$*) -lm

$(B)/sphere1m.off: $(B)/gen_sphere
	$(B)/gen_sphere -f 224 -o $@

bench:
	@tests/deps.sh bench
	@$(MAKE) --no-print-directory bench-build
	@sh bench/run.sh $(B)

bench-build: $(TOOLS) $(BENCHES) $(B)/sphere1m.off

# ---------------------------------------------------------------------------------------------------
$(B):
	@mkdir -p $(B)

clean:
	rm -rf build out
