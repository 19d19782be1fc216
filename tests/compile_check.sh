#!/usr/bin/env bash
# compile_check.sh - compile tests and include policy for the project's stb-style headers.
#
#   tests/compile_check.sh [-o WORKDIR] HEADER...      check these headers
#   tests/compile_check.sh --self-test [-o WORKDIR]    prove the checker catches broken headers
#
# For every header it finds the NAME_IMPLEMENTATION guard (NAME is the header's macro prefix) and checks,
# each as one counted assertion:
#   - include policy: only standard C headers; no header of ours (nor any other non-standard one);
#     SIMD intrinsics headers (immintrin.h, arm_neon.h, ...) only inside a conditional on an opt-in
#     macro with the header's own prefix (e.g. #ifdef NAME_USE_AVX2);
#   - it compiles alone, as C99 and as C++11, with gcc and clang (when present), -Wall -Wextra
#     -pedantic -Werror, in three modes: declarations only, with NAME_IMPLEMENTATION, and with
#     NAME_IMPLEMENTATION + NAME_STATIC;
#   - two translation units (one with the implementation) link into one program (no definitions leak
#     out of the implementation guard);
# and for the whole set, all headers with all implementations in one translation unit (C and C++),
# which catches name collisions between headers.
# Output: "FAIL ..." lines for what fails, "SKIP ..." for what cannot run (with the reason), and one
# line "TESTCOUNT compile_check passed=N failed=N skipped=N" for tests/run.sh. Exit status 1 on failure.
set -u
top=$(cd "$(dirname "$0")/.." && pwd)
work=""
self_test=0
headers=()
while [ $# -gt 0 ]; do
  case "$1" in
    -o) work="$2"; shift 2 ;;
    --self-test) self_test=1; shift ;;
    *) headers+=("$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"); shift ;;
  esac
done
[ -n "$work" ] || work=$(mktemp -d)
mkdir -p "$work"

passed=0; failed=0; skipped=0
pass() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL compile_check: $*"; }
skip() { skipped=$((skipped + $1)); shift; echo "SKIP compile_check: $*"; }

std_headers='assert|complex|ctype|errno|fenv|float|inttypes|iso646|limits|locale|math|setjmp|signal|stdalign|stdarg|stdatomic|stdbool|stddef|stdint|stdio|stdlib|stdnoreturn|string|tgmath|threads|time|uchar|wchar|wctype'
simd_headers='immintrin|emmintrin|xmmintrin|pmmintrin|tmmintrin|smmintrin|nmmintrin|wmmintrin|avxintrin|x86intrin|arm_neon|arm_sve|wasm_simd128'

# The implementation macro named by the header's own guard, e.g. MIO_IMPLEMENTATION.
impl_macro() {
  grep -oE '^[[:space:]]*#[[:space:]]*if(def|[[:space:]]+defined[[:space:]]*\(?)[[:space:]]*[A-Z0-9_]+_IMPLEMENTATION' "$1" \
    | grep -oE '[A-Z0-9_]+_IMPLEMENTATION' | head -n 1
}

# Prints one line per include that breaks the policy; empty output means the header is clean.
include_violations() {
  local h="$1" prefix="$2"
  awk -v std="^($std_headers)\\.h$" -v simd="^($simd_headers)\\.h$" -v pre="$prefix" '
    # true when the line names a PREFIX_ macro other than the guard, IMPLEMENTATION and STATIC ones
    function names_optin(line,   m) {
      while (match(line, pre "_[A-Z0-9_]+")) {
        m = substr(line, RSTART, RLENGTH); line = substr(line, RSTART + RLENGTH)
        if (m != pre "_IMPLEMENTATION" && m != pre "_STATIC" && m != pre "_H") return 1
      }
      return 0
    }
    function optin(   i) { for (i = 1; i <= depth; i++) if (ok[i]) return 1; return 0 }
    # directives inside /* */ comments (a doc block showing how to include the header) do not count
    {
      line = $0; out = ""
      while (length(line) > 0) {
        if (incomment) {
          e = index(line, "*/"); if (!e) { line = ""; break }
          line = substr(line, e + 2); incomment = 0
        } else {
          b = index(line, "/*"); if (!b) { out = out line; break }
          out = out substr(line, 1, b - 1); line = substr(line, b + 2); incomment = 1
        }
      }
      $0 = out
    }
    /^[ \t]*#[ \t]*if/ {
      depth++
      # an opt-in conditional names a macro with the header prefix and does not negate it
      ok[depth] = names_optin($0) && ($0 !~ /ifndef/) && ($0 !~ ("!" "[ \t]*defined"))
      next
    }
    /^[ \t]*#[ \t]*elif/ { ok[depth] = names_optin($0) && ($0 !~ ("!" "[ \t]*defined")); next }
    /^[ \t]*#[ \t]*else/ { ok[depth] = 0; next }
    /^[ \t]*#[ \t]*endif/ { if (depth > 0) depth--; next }
    /^[ \t]*#[ \t]*include/ {
      line = $0
      name = line; sub(/^[ \t]*#[ \t]*include[ \t]*[<"]/, "", name); sub(/[>"].*$/, "", name)
      if (name ~ std) next
      if (name ~ simd) { if (!optin()) print FILENAME ":" NR ": SIMD header <" name "> outside an opt-in " pre "_ conditional"; next }
      if (name ~ /^(dispmesh|erosion|texel|subdiv4|deform|meshio|render)\.h$/) print FILENAME ":" NR ": includes our header \"" name "\""
      else print FILENAME ":" NR ": includes non-standard header <" name ">"
    }' "$h"
}

have() { command -v "$1" >/dev/null 2>&1; }
cc_list=(); for c in gcc clang; do have "$c" && cc_list+=("$c"); done
cxx_list=(); for c in g++ clang++; do have "$c" && cxx_list+=("$c"); done
have clang || skip 8 "clang not installed: compile checks with clang/clang++ skipped (apt-get install clang)"
have g++ || skip 3 "g++ not installed: C++ compile checks with g++ skipped (apt-get install g++)"

cflags=(-std=c99 -Wall -Wextra -pedantic -Werror)
cxxflags=(-std=c++11 -Wall -Wextra -pedantic -Werror)

# try_compile LABEL COMPILER FLAGS-NAME SOURCE-FILE: compiles to an object, records pass or fail.
try_compile() {
  local label="$1" comp="$2" src="$4"; local -n fl="$3"
  if "$comp" "${fl[@]}" -c "$src" -o "$src.o" 2>"$src.err"; then pass; return 0; fi
  fail "$label: $comp $(head -c 400 "$src.err" | tr '\n' ' ')"
  return 1
}

check_header() {
  local h="$1" base macro prefix d
  base=$(basename "$h" .h)
  macro=$(impl_macro "$h")
  if [ -z "$macro" ]; then fail "$h: no NAME_IMPLEMENTATION guard found"; return; fi
  pass
  prefix=${macro%_IMPLEMENTATION}
  local v; v=$(include_violations "$h" "$prefix")
  if [ -n "$v" ]; then fail "$h include policy: $(echo "$v" | tr '\n' ' ')"; else pass; fi
  d="$work/$base"; mkdir -p "$d"
  printf '#include "%s"\nint main(void) { return 0; }\n' "$h" > "$d/decl.c"
  printf '#define %s\n#include "%s"\nint main(void) { return 0; }\n' "$macro" "$h" > "$d/impl.c"
  printf '#define %s\n#define %s_STATIC\n#include "%s"\nint main(void) { return 0; }\n' "$macro" "$prefix" "$h" > "$d/static.c"
  local mode comp
  for mode in decl impl static; do
    cp "$d/$mode.c" "$d/$mode.cpp"
    for comp in "${cc_list[@]}"; do try_compile "$h $mode C99" "$comp" cflags "$d/$mode.c"; done
    for comp in "${cxx_list[@]}"; do try_compile "$h $mode C++11" "$comp" cxxflags "$d/$mode.cpp"; done
  done
  # two translation units, the implementation in one of them
  printf '#define %s\n#include "%s"\n' "$macro" "$h" > "$d/tu_a.c"
  printf '#include "%s"\nint main(void) { return 0; }\n' "$h" > "$d/tu_b.c"
  for comp in "${cc_list[@]}"; do
    if "$comp" "${cflags[@]}" "$d/tu_a.c" "$d/tu_b.c" -o "$d/tu_$comp" -lm 2>"$d/tu.err"; then pass
    else fail "$h two-TU link with $comp: $(head -c 400 "$d/tu.err" | tr '\n' ' ')"; fi
  done
}

check_together() {
  local d="$work/together" h macro
  mkdir -p "$d"; : > "$d/all.c"
  for h in "$@"; do
    macro=$(impl_macro "$h"); [ -n "$macro" ] && printf '#define %s\n' "$macro" >> "$d/all.c"
  done
  for h in "$@"; do printf '#include "%s"\n' "$h" >> "$d/all.c"; done
  printf 'int main(void) { return 0; }\n' >> "$d/all.c"
  cp "$d/all.c" "$d/all.cpp"
  local comp
  for comp in "${cc_list[@]}"; do try_compile "all headers in one TU (C99)" "$comp" cflags "$d/all.c"; done
  for comp in "${cxx_list[@]}"; do try_compile "all headers in one TU (C++11)" "$comp" cxxflags "$d/all.cpp"; done
}

if [ "$self_test" = 1 ]; then
  # Each fixture is a small header that breaks one rule (or none). The checker, run on it alone, must
  # report a failure exactly for the broken ones. This is what makes a green compile check mean something.
  fx="$top/tests/fixtures/compile_check"
  expect() { # expect good|bad KEYWORD HEADER...: a bad case must fail with KEYWORD in a FAIL line
    local want="$1" key="$2" out rc name; shift 2
    name=$(basename "$1" .h)
    out=$("$0" -o "$work/self/$name" "$@" 2>&1); rc=$?
    if [ "$want" = bad ] && [ $rc -ne 0 ] && echo "$out" | grep '^FAIL' | grep -qF -- "$key"; then pass
    elif [ "$want" = good ] && [ $rc -eq 0 ] && ! echo "$out" | grep -q '^FAIL'; then pass
    else fail "self-test: $name should be $want ($key) but the checker said: $(echo "$out" | grep -E '^(FAIL|TESTCOUNT)' | head -3 | tr '\n' ' ')"; fi
  }
  expect good - "$fx/good.h"
  expect good - "$fx/good_simd_optin.h"
  expect good - "$fx/good.h" "$fx/good_simd_optin.h"
  expect bad "no NAME_IMPLEMENTATION guard" "$fx/bad_no_guard.h"
  expect bad "includes our header" "$fx/bad_include_ours.h"
  expect bad "non-standard header <unistd.h>" "$fx/bad_nonstd.h"
  expect bad "SIMD header <immintrin.h> outside" "$fx/bad_simd.h"
  expect bad "SIMD header <immintrin.h> outside" "$fx/bad_simd_negated.h"
  expect bad "impl C++11" "$fx/bad_cxx.h"
  expect bad "impl C99" "$fx/bad_warning.h"
  expect bad "static C99" "$fx/bad_static.h"
  expect bad "two-TU link" "$fx/bad_definition_outside.h"
  expect bad "one TU" "$fx/good.h" "$fx/bad_collision.h"
  echo "TESTCOUNT compile_check_self_test passed=$passed failed=$failed skipped=$skipped"
  [ $failed -eq 0 ]; exit
fi

if [ ${#headers[@]} -eq 0 ]; then
  skip 1 "no headers given"
else
  for h in "${headers[@]}"; do check_header "$h"; done
  check_together "${headers[@]}"
fi
echo "TESTCOUNT compile_check passed=$passed failed=$failed skipped=$skipped"
[ $failed -eq 0 ]
