#!/bin/sh
# erosion_simd_same.sh BUILD_DIR - erosion.h's ERO_USE_AVX2 path must give the portable path's bits:
# runs test_erosion --digest as built portable and with ERO_USE_AVX2 (x86-64 only; a counted skip
# when not built or on a CPU without AVX2) and compares.
B="$1"
pass=0; fail=0; skip=0
ref=$("$B/test_erosion" --digest) || { echo "FAIL portable digest run"; fail=1; }
echo "portable $ref"
prog="$B/test_erosion_avx2"
if [ ! -x "$prog" ]; then
  echo "SKIP avx2: not built (not an x86-64 machine)"; skip=1
elif ! grep -qw avx2 /proc/cpuinfo 2>/dev/null; then
  echo "SKIP avx2: this CPU has no AVX2"; skip=1
else
  got=$("$prog" --digest)
  echo "avx2 $got"
  if [ -n "$ref" ] && [ "$got" = "$ref" ]; then pass=1; else echo "FAIL avx2: bits differ from the portable path"; fail=$((fail + 1)); fi
fi
echo "TESTCOUNT erosion_simd_same passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
