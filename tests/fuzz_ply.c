/* fuzz_ply.c - fuzz target for the PLY reader of examples/meshio.h (checks in fuzz_meshio.h)
   libFuzzer: clang -g -O1 -fsanitize=fuzzer,address,undefined tests/fuzz_ply.c -o fuzz_ply
   plain:     gcc -std=c99 -g -O1 tests/fuzz_ply.c tests/fuzz_main.c -o fuzz_ply && ./fuzz_ply tests/fuzz/corpus/ply */
#define FUZZ_FORMAT MIO_FORMAT_PLY
#include "fuzz_meshio.h"
