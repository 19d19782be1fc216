/* fuzz_stl.c - fuzz target for the STL reader of examples/meshio.h (checks in fuzz_meshio.h)
   libFuzzer: clang -g -O1 -fsanitize=fuzzer,address,undefined tests/fuzz_stl.c -o fuzz_stl
   plain:     gcc -std=c99 -g -O1 tests/fuzz_stl.c tests/fuzz_main.c -o fuzz_stl && ./fuzz_stl tests/fuzz/corpus/stl */
#define FUZZ_FORMAT MIO_FORMAT_STL
#include "fuzz_meshio.h"
