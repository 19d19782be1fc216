# texel.h (issue 19): tests and the grass example
C_TESTS += $(B)/test_texel $(B)/test_texel_tvt
EXAMPLES += $(B)/grass
# the bench is C (it includes examples/grass.c for the mountain's driver)
BENCHES += $(B)/bench_texel
$(B)/bench_texel: bench/bench_texel.c examples/grass.c $(ALLDEPS) | $(B)
	$(CC) $(CFLAGS_ALL) -DNDEBUG -DBENCH_FLAGS='"$(CC) $(CFLAGS_ALL) -DNDEBUG"' $< -o $@ -lm
C_TESTS += $(B)/test_texel_shell
C_TESTS += $(B)/test_texel_mesh
