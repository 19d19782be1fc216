# erosion.h (issue 17): the tests
C_TESTS += $(B)/test_erosion
# and with its AVX2 path (tests/erosion_simd_same.sh compares their bits)
ifeq ($(shell uname -m),x86_64)
  C_TESTS += $(B)/test_erosion_avx2
endif
$(B)/test_erosion_avx2: tests/test_erosion.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DERO_USE_AVX2 -mavx2 $< -o $@ -lm
# the bench is C (dispmesh.h makes the surface map, meshio.h reads the mesh), with erosion.h's AVX2
# path where the CPU has AVX2 (as its doc recommends; the stream loop is in the same binary)
BENCHES += $(B)/bench_erosion
BENCH_FLAGS_erosion = $(if $(HAVE_AVX2),-DERO_USE_AVX2 -mavx2)
$(B)/bench_erosion: bench/bench_erosion.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DNDEBUG $(BENCH_FLAGS_erosion) -DBENCH_FLAGS='"$(CC) $(CFLAGS_ALL) -DNDEBUG $(BENCH_FLAGS_erosion)"' $< -o $@ -lm
# the example program
EXAMPLES += $(B)/erode
