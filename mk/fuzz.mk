# The fuzz targets of issue 21 point 4 for deform.h, texel.h, examples/relief.h and dispmesh.h: built
# by the Makefile's fuzz_% rules (plain, replayed on tests/fuzz/corpus/<name> by tests.list's
# fuzz_regress_<name>; and with libFuzzer by `make fuzz`). tests/fuzz_deform.c holds the byte
# reader and failing allocator that the others include.
FUZZ_FMTS += deform
FUZZ_FMTS += texel relief dispmesh
# the targets that include fuzz_deform.c's helpers rebuild when it changes
$(B)/fuzz_texel $(B)/fuzz/fuzz_texel $(B)/fuzz_relief $(B)/fuzz/fuzz_relief \
  $(B)/fuzz_dispmesh $(B)/fuzz/fuzz_dispmesh: tests/fuzz_deform.c
# erosion.h (issue 17): grids, maps, materials and options from the bytes
FUZZ_FMTS += erosion
$(B)/fuzz_erosion $(B)/fuzz/fuzz_erosion: tests/fuzz_deform.c
