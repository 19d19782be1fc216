/* fuzz_obj.c - fuzz target for the OBJ reader of examples/meshio.h (checks in fuzz_meshio.h)
   libFuzzer: clang -g -O1 -fsanitize=fuzzer,address,undefined tests/fuzz_obj.c -o fuzz_obj
   plain:     gcc -std=c99 -g -O1 tests/fuzz_obj.c tests/fuzz_main.c -o fuzz_obj && ./fuzz_obj tests/fuzz/corpus/obj */
#define FUZZ_FORMAT MIO_FORMAT_OBJ
#include "fuzz_meshio.h"
