/* fuzz_off.c - fuzz target for the OFF reader of examples/meshio.h (checks in fuzz_meshio.h)
   libFuzzer: clang -g -O1 -fsanitize=fuzzer,address,undefined tests/fuzz_off.c -o fuzz_off
   plain:     gcc -std=c99 -g -O1 tests/fuzz_off.c tests/fuzz_main.c -o fuzz_off && ./fuzz_off tests/fuzz/corpus/off */
#define FUZZ_FORMAT MIO_FORMAT_OFF
#include "fuzz_meshio.h"
