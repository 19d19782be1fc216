#!/bin/sh
# simd_same.sh BUILD_DIR - dispmesh.h's SIMD paths must answer every query exactly as the portable
# path does: runs test_dispmesh_bvh --digest as built portable, with DM_USE_SSE2 and with
# DM_USE_AVX2 (x86-64 only; the AVX2 runs are counted skips on a CPU without AVX2) and compares;
# then test_dispmesh_digest as built with DM_USE_AVX2 (the shell constraint's vector search), which
# must meet the portable build's recorded digests.
B="$1"
pass=0; fail=0; skip=0
ref=$("$B/test_dispmesh_bvh" --digest) || { echo "FAIL portable digest run"; fail=1; }
echo "$ref"
for v in sse2 avx2; do
  prog="$B/test_dispmesh_bvh_$v"
  if [ ! -x "$prog" ]; then echo "SKIP $v: not built (not an x86-64 machine)"; skip=$((skip + 1)); continue; fi
  if [ $v = avx2 ] && ! grep -qw avx2 /proc/cpuinfo 2>/dev/null; then
    echo "SKIP avx2: this CPU has no AVX2"; skip=$((skip + 1)); continue
  fi
  got=$("$prog" --digest)
  echo "$got"
  if [ "$(echo "$got" | grep digest)" = "$(echo "$ref" | grep digest)" ] && [ -n "$ref" ]; then
    pass=$((pass + 1))
  else
    echo "FAIL $v: answers differ from the portable path"; fail=$((fail + 1))
  fi
done
prog="$B/test_dispmesh_digest_avx2"
if [ ! -x "$prog" ]; then echo "SKIP digest avx2: not built (not an x86-64 machine)"; skip=$((skip + 1))
elif ! grep -qw avx2 /proc/cpuinfo 2>/dev/null; then echo "SKIP digest avx2: this CPU has no AVX2"; skip=$((skip + 1))
elif "$prog" >"$B/simd_same_digest.log" 2>&1; then
  echo "digest avx2: the recorded digests"; pass=$((pass + 1))
else
  echo "FAIL digest avx2: the AVX2 build's digests differ from the recorded ones (see $B/simd_same_digest.log):"
  grep -E '^FAIL' "$B/simd_same_digest.log" | head -n 20; fail=$((fail + 1))
fi
echo "TESTCOUNT simd_same passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
