# erosion.h (issue 17): the tests
C_TESTS += $(B)/test_erosion
# the bench is C (dispmesh.h makes the surface map, meshio.h reads the mesh)
BENCHES += $(B)/bench_erosion
$(B)/bench_erosion: bench/bench_erosion.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DNDEBUG -DBENCH_FLAGS='"$(CC) $(CFLAGS_ALL) -DNDEBUG"' $< -o $@ -lm
# the example program
EXAMPLES += $(B)/erode
