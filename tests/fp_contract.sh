#!/usr/bin/env bash
# fp_contract.sh BUILD_DIR - the bits and the watertightness must not depend on the compiler's FMA
# contraction (issue 21 point 1). Under each configuration
#   gnu99      gcc -std=gnu99 -march=native -O2                      (GNU C contracts: fast)
#   cxx17      g++ -std=c++17 -march=native -O2                      (C++ contracts: fast)
#   clang      clang -std=c99 -march=native -O2                      (clang's default: on)
#   gcc-fast   gcc -std=c99 -ffp-contract=fast -march=native -O2
# it builds, into BUILD_DIR/fpc/<configuration>/, and runs
#   test_dispmesh_bvh --watertight   rays at every vertex and edge midpoint of two closed spheres,
#                                    from outside and from inside: none may miss or pass through;
#   test_dispmesh_digest             the digests of dm_simplify, dm_parameterize, dm_bake, dm_reconstruct;
#   test_deform_chol --digests       the digests of dfm_chol_factor and dfm_chol_solve;
# each must pass: the digests equal the ones recorded in the tests. A configuration whose compiler
# is missing is a counted skip, named; so is the whole matrix on an x86-64 CPU without FMA (nothing
# could be contracted there). Binaries are rebuilt when a header, a test or the command changes.
# clang -ffp-contract=fast is not in the matrix: clang ignores the headers' pragmas under it (their
# LIMITS say so). FPC_INCLUDE=DIR puts DIR first on the include path (to try header copies).
set -u
top=$(cd "$(dirname "$0")/.." && pwd)
B="${1:?usage: fp_contract.sh BUILD_DIR}"
case "$B" in /*) ;; *) B="$(pwd)/$B" ;; esac
cd "$top" || exit 1
inc="${FPC_INCLUDE:+-I$FPC_INCLUDE }-I. -Iexamples -Itests -Ibench"
warn="-Wall -Wextra -pedantic -Werror"
configs="gnu99 cxx17 clang gcc-fast"
pass=0; fail=0; skip=0

command_of() {
  case "$1" in
    gnu99) echo "gcc -std=gnu99 -march=native -O2" ;;
    cxx17) echo "g++ -x c++ -std=c++17 -march=native -O2" ;;
    clang) echo "clang -std=c99 -march=native -O2" ;;
    gcc-fast) echo "gcc -std=c99 -ffp-contract=fast -march=native -O2" ;;
  esac
}

# the sources a binary depends on: its test, every header the tests can include, this script
deps() {
  echo "tests/$1.c" "$0" ./*.h examples/*.h tests/*.h bench/*.h
  [ -n "${FPC_INCLUDE:-}" ] && echo "$FPC_INCLUDE"/*.h
}

stale() { # stale BINARY COMMAND TEST: no binary, another command, or a newer source
  [ -x "$1" ] && [ -f "$1.cmd" ] && [ "$(cat "$1.cmd")" = "$2" ] || return 0
  for f in $(deps "$3"); do [ "$f" -nt "$1" ] && return 0; done
  return 1
}

if [ "$(uname -m)" = x86_64 ] && ! grep -qw fma /proc/cpuinfo 2>/dev/null; then
  echo "SKIP fp_contract: this CPU has no FMA, so no configuration can contract (the matrix could not fail)"
  echo "TESTCOUNT fp_contract passed=0 failed=0 skipped=12"
  exit 0
fi

for cfg in $configs; do
  cmd=$(command_of $cfg)
  cc=${cmd%% *}
  if ! command -v "$cc" >/dev/null 2>&1; then
    echo "SKIP $cfg: $cc is not installed ($cmd)"
    skip=$((skip + 3))
    continue
  fi
  dir="$B/fpc/$cfg"
  mkdir -p "$dir"
  for run in "test_dispmesh_bvh --watertight" test_dispmesh_digest "test_deform_chol --digests"; do
    t=${run%% *}
    bin="$dir/$t"
    full="$cmd $warn $inc tests/$t.c -o $bin -lm"
    if stale "$bin" "$full" "$t"; then
      rm -f "$bin" "$bin.cmd"
      if ! $full >"$bin.build.log" 2>&1; then
        echo "FAIL $cfg $t: does not build ($full):"
        head -n 20 "$bin.build.log" | sed 's/^/    /'
        fail=$((fail + 1))
        continue
      fi
      echo "$full" >"$bin.cmd"
    fi
    args=${run#"$t"}
    "$bin" $args >"$bin.log" 2>&1
    rc=$?
    if [ $rc -eq 0 ] && grep -q '^TESTCOUNT .* failed=0 ' "$bin.log"; then
      pass=$((pass + 1))
      echo "ok   $cfg $run ($(grep '^TESTCOUNT' "$bin.log" | sed 's/.* passed=\([0-9]*\).*/\1/') checks)"
    else
      fail=$((fail + 1))
      echo "FAIL $cfg $run: exit status $rc ($cmd; log $bin.log):"
      grep -E '^  note:|rays at vertices' "$bin.log" | head -n 6 | sed 's/^/    /'
    fi
  done
done
echo "TESTCOUNT fp_contract passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
