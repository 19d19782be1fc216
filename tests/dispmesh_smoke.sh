#!/bin/sh
# dispmesh_smoke.sh BUILD_DIR - smoke test of examples/dispmesh.c (paper 000 end to end) on the generated
# brick, and its refusal of bad input. Checks properties only, never timings:
#   --brick --faces 12 --res 128: exit 0; the five files exist and are not empty; the PNGs pass pngcheck
#   (counted skip without it); the RESULT line has every field, numeric; faces <= 12; rms < base_only_rms;
#   flagged <= 0.01; target = 12.
#   an unwelded copy of the brick (ASCII STL, every triangle its own vertices): welded, exit 0, faces <= 12;
#   two octahedra whose corners share a position: the two vertices stay apart (no weld into a pinch);
#   two octahedra that run through each other: a note says so (not for the touching pair, nor the brick);
#   the brick wound clockwise, scrambled (a third of its faces turned) and with faces written twice:
#   turned back and the repeats dropped (said), each the same RESULT as the brick itself.
#   bad input (missing file, malformed files of our own and, when installed, of assimp-testmodels,
#   a mesh without extent, an unwritable prefix, a map too coarse for the base so that base triangles
#   get no texel): exit 1 (failure); bad arguments (--res 0, a bad number, no input, an unknown
#   option): exit 2 (usage); each with a "dispmesh:" message, no sanitizer report, no RESULT line
#   and no PREFIX_* file left.
# `make test` does not build the examples: the binary is built here with make when it is missing (with
# the sanitizer flags of `make sanitize` when TEST_SANITIZE=1).
B="$1"
top=$(cd "$(dirname "$0")/.." && pwd)
prog="$B/dispmesh"
pass=0; fail=0; skip=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
check() { # check DESCRIPTION CONDITION-COMMAND...
  what="$1"; shift
  if "$@"; then ok; else bad "$what"; fi
}

if [ "${TEST_SANITIZE:-0}" = 1 ]; then
  make -s -C "$top" --no-print-directory B="$B" OPT="-O1 -g" \
    XFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" "$prog" >&2
else
  make -s -C "$top" --no-print-directory B="$B" "$prog" >&2
fi
made=$?
if [ $made -ne 0 ] || [ ! -x "$prog" ]; then
  echo "FAIL $prog could not be built (make $prog)"
  echo "TESTCOUNT dispmesh_smoke passed=0 failed=1 skipped=0"
  exit 1
fi
case "$prog" in /*) ;; *) prog="$top/$prog" ;; esac

tmp=$(mktemp -d "${TMPDIR:-/tmp}/dispmesh_smoke.XXXXXX") || { echo "FAIL mktemp"; exit 1; }
trap 'rm -rf "$tmp"' EXIT

# ---- the brick ------------------------------------------------------------------------------------
"$prog" --brick --faces 12 --res 128 -o "$tmp/brick" >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
cat "$tmp/err.txt"
cat "$tmp/out.txt"
check "brick run exits 0 (status $rc)" [ $rc -eq 0 ]
check "no sanitizer report" sh -c "! grep -q -E 'Sanitizer|runtime error' '$tmp/err.txt'"
for f in base.obj disp.pfm normal.png recon.obj views.png; do
  check "brick_$f exists and is not empty" [ -s "$tmp/brick_$f" ]
done
if command -v pngcheck >/dev/null 2>&1; then
  for f in normal.png views.png; do
    if pngcheck -q "$tmp/brick_$f" >"$tmp/pngcheck.txt" 2>&1; then ok; else bad "pngcheck brick_$f: $(cat "$tmp/pngcheck.txt")"; fi
  done
else
  echo "SKIP pngcheck: not installed (apt-get install pngcheck)"; skip=$((skip + 2))
fi
result=$(grep '^RESULT dispmesh ' "$tmp/out.txt" | tail -n 1)
check "one RESULT dispmesh line" [ -n "$result" ]
field() { echo "$result" | tr ' ' '\n' | sed -n "s/^$1=//p"; }
isnum() { echo "$1" | grep -q -E '^[-+]?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$'; }
for k in target faces res rms max base_only_rms base_only_max unconstrained_rms equal_bytes_rms equal_bytes_max flagged bake_ms total_ms; do
  v=$(field $k)
  check "RESULT field $k is a number ('$v')" isnum "$v"
done
faces=$(field faces); rms=$(field rms); base_rms=$(field base_only_rms); flagged=$(field flagged)
num() { awk "BEGIN { exit !($*) }" 2>/dev/null; }
if isnum "$faces" && num "$faces <= 12"; then ok; else bad "brick base has $faces triangles, more than --faces 12"; fi
if isnum "$rms" && isnum "$base_rms" && num "$rms < $base_rms"; then ok
else bad "base + map rms ($rms) is not below the base-only rms ($base_rms)"; fi
if isnum "$flagged" && num "$flagged <= 0.01"; then ok; else bad "flagged texels $flagged > 0.01"; fi
if isnum "$faces" && [ -s "$tmp/brick_base.obj" ]; then
  nf=$(grep -c '^f ' "$tmp/brick_base.obj")
  check "brick_base.obj has the RESULT's $faces faces (has $nf)" [ "$nf" = "$faces" ]
fi

check "RESULT target is --faces 12 ($(field target))" [ "$(field target)" = 12 ]

# ---- an unwelded mesh: the generated brick's 496 triangles as an ASCII STL -------------------------
if "$prog" --brick --faces 496 --res 256 --no-views -o "$tmp/full" >/dev/null 2>"$tmp/full_err.txt"; then
  awk 'BEGIN { print "solid brick" } /^v / { n++; x[n] = $2; y[n] = $3; z[n] = $4 }
       /^f / { print " facet normal 0 0 0"; print "  outer loop"
               for (i = 2; i <= 4; i++) { split($i, a, "/"); print "   vertex " x[a[1]] " " y[a[1]] " " z[a[1]] }
               print "  endloop"; print " endfacet" } END { print "endsolid brick" }' "$tmp/full_base.obj" >"$tmp/soup.stl"
  "$prog" "$tmp/soup.stl" --faces 12 --res 128 --no-views -o "$tmp/soup" >"$tmp/soup_out.txt" 2>"$tmp/soup_err.txt"
  rc=$?
  check "unwelded STL run exits 0 (status $rc): $(tail -n 2 "$tmp/soup_err.txt")" [ $rc -eq 0 ]
  check "unwelded STL is welded: $(grep -m1 welded "$tmp/soup_err.txt")" grep -q 'welded vertices at equal positions: 1488 -> 250' "$tmp/soup_err.txt"
  result=$(grep '^RESULT dispmesh ' "$tmp/soup_out.txt" | tail -n 1)
  faces=$(field faces)
  if isnum "$faces" && num "$faces <= 12"; then ok; else bad "welded STL base has '$faces' triangles, more than --faces 12"; fi
else
  bad "brick at --faces 496 failed: $(tail -n 3 "$tmp/full_err.txt")"
fi

# ---- two octahedra whose corners share a position: kept apart, not welded into a pinch ------------
octahedra() { # octahedra SPACING FILE: two unit octahedra as one OFF mesh, centres SPACING apart along x
  awk -v sp="$1" 'BEGIN { print "OFF"; print "12 16 0"
    for (o = 0; o < 2; o++) { c = sp * o
      print c + 1, 0, 0; print c - 1, 0, 0; print c, 1, 0; print c, -1, 0; print c, 0, 1; print c, 0, -1 }
    for (o = 0; o < 2; o++) { b = 6 * o
      print 3, b + 0, b + 2, b + 4; print 3, b + 2, b + 1, b + 4; print 3, b + 1, b + 3, b + 4; print 3, b + 3, b + 0, b + 4
      print 3, b + 2, b + 0, b + 5; print 3, b + 1, b + 2, b + 5; print 3, b + 3, b + 1, b + 5; print 3, b + 0, b + 3, b + 5 } }' >"$2"
}
octahedra 2 "$tmp/pinch.off"
"$prog" "$tmp/pinch.off" --faces 16 --res 64 --no-views -o "$tmp/pinch" >/dev/null 2>"$tmp/pinch_err.txt"
check "corners meeting at a point stay apart: $(grep -m1 apart "$tmp/pinch_err.txt")" \
  grep -q '^dispmesh: 1 vertices share a position with another but meet it only at a point' "$tmp/pinch_err.txt"
check "and are not welded: $(grep -m1 'vertices,' "$tmp/pinch_err.txt")" grep -q 'pinch.off: 12 vertices, 16 triangles' "$tmp/pinch_err.txt"

# ---- two octahedra that run through each other: said; the corner-touching pair and the brick are not --
octahedra 0.8 "$tmp/cross.off"
"$prog" "$tmp/cross.off" --faces 16 --res 64 --no-views -o "$tmp/cross" >/dev/null 2>"$tmp/cross_err.txt"
check "two interpenetrating octahedra: the note says the surface runs through itself ($(grep -m1 'runs through' "$tmp/cross_err.txt"))" \
  grep -q '^dispmesh: note: the surface runs through itself: [1-9][0-9]* of its edges' "$tmp/cross_err.txt"
check "octahedra touching at a corner: no such note" sh -c "! grep -q 'runs through itself' '$tmp/pinch_err.txt'"
check "the brick: no such note" sh -c "! grep -q 'runs through itself' '$tmp/full_err.txt'"

# ---- the brick as exporters mangle it: the same RESULT ----------------------------------------------
# its 496 triangles as an OFF file (reference); wound clockwise (every face turned); scrambled (every
# third face turned); with its first 40 faces written again (every other one turned). The tool turns
# them back (dm_orient) and drops the repeats, so each gives the reference's RESULT, bit for bit.
if [ -s "$tmp/full_base.obj" ]; then
  for v in ref cw scrambled repeats; do
    awk -v v="$v" '/^v / { n++; p[n] = $2 " " $3 " " $4 }
      /^f / { m++; for (i = 2; i <= 4; i++) { split($i, a, "/"); c[m, i - 1] = a[1] - 1 } }
      END { extra = v == "repeats" ? 40 : 0; print "OFF"; print n, m + extra, 0
            for (i = 1; i <= n; i++) print p[i]
            for (k = 1; k <= m + extra; k++) { f = k <= m ? k : k - m
              t = (v == "cw") || (v == "scrambled" && k % 3 == 0) || (k > m && k % 2 == 0)
              if (t) print 3, c[f, 1], c[f, 3], c[f, 2]; else print 3, c[f, 1], c[f, 2], c[f, 3] } }' \
      "$tmp/full_base.obj" >"$tmp/brick_$v.off"
    "$prog" "$tmp/brick_$v.off" --faces 48 --res 128 --no-views -o "$tmp/m_$v" >"$tmp/m_${v}_out.txt" 2>"$tmp/m_${v}_err.txt"
    rc=$?
    check "brick ($v) exits 0 (status $rc): $(tail -n 1 "$tmp/m_${v}_err.txt")" [ $rc -eq 0 ]
  done
  same() { grep '^RESULT dispmesh ' "$1" | sed 's/ bake_ms=.*//'; }
  ref=$(same "$tmp/m_ref_out.txt")
  check "the brick's reference run has a RESULT" [ -n "$ref" ]
  for v in cw scrambled repeats; do
    check "brick ($v): the reference's RESULT ($(same "$tmp/m_${v}_out.txt") vs $ref)" [ "$(same "$tmp/m_${v}_out.txt")" = "$ref" ]
  done
  check "brick (cw): all 496 turned, said" grep -q '^dispmesh: note: 496 of 496 triangles turned' "$tmp/m_cw_err.txt"
  check "brick (scrambled): 165 turned, said" grep -q '^dispmesh: note: 165 of 496 triangles turned' "$tmp/m_scrambled_err.txt"
  check "brick (repeats): 40 dropped, said" grep -q "^dispmesh: note: 40 triangles repeat another's corners: dropped" "$tmp/m_repeats_err.txt"
  check "brick (ref): nothing turned or dropped" sh -c "! grep -q -E 'turned|repeat' '$tmp/m_ref_err.txt'"
fi

# ---- a target the paper's constraints cannot reach: the brick's box has 12 faces -----------------
"$prog" --brick --strict --faces 8 --res 128 --no-views -o "$tmp/b8" >"$tmp/b8_out.txt" 2>"$tmp/b8_err.txt"
rc=$?
result=$(grep '^RESULT dispmesh ' "$tmp/b8_out.txt" | tail -n 1)
check "--strict --faces 8 exits 0 (status $rc)" [ $rc -eq 0 ]
check "--strict --faces 8: RESULT says target=8 faces=12 fallback=0 ($result)" [ "$(field target) $(field faces) $(field fallback)" = "8 12 0.0000" ]
check "--strict --faces 8: the note says why and what the default does" grep -q 'shell constraint vetoed every remaining collapse.*without --strict' "$tmp/b8_err.txt"

# ---- --samples: the distances' sample count; the same base and map, other distance estimates ---------
"$prog" --brick --faces 48 --res 128 --no-views --samples 5000 -o "$tmp/s5" >"$tmp/s5_out.txt" 2>"$tmp/s5_err.txt"
rc=$?
result=$(grep '^RESULT dispmesh ' "$tmp/s5_out.txt" | tail -n 1)
check "--samples 5000 exits 0 with a RESULT line (status $rc)" [ $rc -eq 0 -a -n "$result" ]
"$prog" --brick --faces 48 --res 128 --no-views -o "$tmp/s0" >/dev/null 2>&1
check "--samples changes no output file" cmp -s "$tmp/s5_disp.pfm" "$tmp/s0_disp.pfm"

# ---- bad input --------------------------------------------------------------------------------------
refuse() { # refuse DESCRIPTION STATUS ARGS...: exit STATUS, a message, no sanitizer report, no x_* file
  what="$1"; want="$2"; shift 2
  rm -f "$tmp"/x_*
  "$prog" "$@" >"$tmp/bad_out.txt" 2>"$tmp/bad_err.txt"
  rc=$?
  if [ $rc -eq "$want" ] && grep -q 'dispmesh' "$tmp/bad_err.txt" && ! ls "$tmp" | grep -q '^x_' &&
     ! grep -q -E 'Sanitizer|runtime error' "$tmp/bad_err.txt" && ! grep -q '^RESULT' "$tmp/bad_out.txt"; then
    ok
  else
    bad "$what: status $rc (expected $want); files: $(ls "$tmp" | grep '^x_' | tr '\n' ' '); stderr: $(head -c 400 "$tmp/bad_err.txt")"
  fi
}
printf 'v 0 0 0\nv 1 0 0\n' >"$tmp/two_coords.obj"; printf 'v 1 2\nf 1 2 3\n' >>"$tmp/two_coords.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >"$tmp/index.obj"
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n' >"$tmp/short.off"
printf 'v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/nan.obj"
printf 'v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n' >"$tmp/point.obj"
: >"$tmp/empty.obj"
refuse "missing file" 1 "$tmp/does_not_exist.obj" -o "$tmp/x"
refuse "vertex with two coordinates" 1 "$tmp/two_coords.obj" -o "$tmp/x"
refuse "face index out of range" 1 "$tmp/index.obj" -o "$tmp/x"
refuse "truncated OFF" 1 "$tmp/short.off" -o "$tmp/x"
refuse "NaN coordinate" 1 "$tmp/nan.obj" -o "$tmp/x"
refuse "mesh without extent" 1 "$tmp/point.obj" -o "$tmp/x"
refuse "empty file" 1 "$tmp/empty.obj" -o "$tmp/x"
refuse "--res 0" 2 --brick --res 0 -o "$tmp/x"
refuse "--faces abc" 2 --brick --faces abc -o "$tmp/x"
refuse "--res too small for the charts" 1 --brick --faces 496 --res 8 -o "$tmp/x"
refuse "--res too coarse for the base (triangles without a texel)" 1 --brick --faces 496 --res 32 -o "$tmp/x"
refuse "--fallback to 8 faces: most texels find no surface (a broken result)" 1 --brick --fallback --faces 8 --res 128 -o "$tmp/x"
refuse "--faces 8 (the fallback is the default): the same broken result" 1 --brick --faces 8 --res 128 -o "$tmp/x"
refuse "unwritable prefix" 1 --brick --res 64 -o "$tmp/no/such/dir/x"
refuse "no input" 2 -o "$tmp/x"
refuse "--faces 4294967297" 2 --brick --faces 4294967297 -o "$tmp/x"
refuse "--min-quality nan" 2 --brick --min-quality nan -o "$tmp/x"
refuse "--samples 10 (below 1000)" 2 --brick --samples 10 -o "$tmp/x"
refuse "--res without a value" 2 --brick -o "$tmp/x" --res
refuse "an unknown option" 2 --brick --bogus -o "$tmp/x"
# ---- a write cut short: the file-size limit (ulimit -f, SIGXFSZ ignored, so write() fails with EFBIG as
# on a full disk) lets the small PREFIX_base.obj through and stops the 64 KB PREFIX_disp.pfm: exit 1
# naming the cause, no PREFIX_* file and no .tmp left, and a PREFIX_base.obj that existed is unchanged
printf 'old\n' >"$tmp/w_base.obj"
sh -c "ulimit -f 8; trap '' XFSZ; exec '$prog' --brick --faces 12 --res 128 -o '$tmp/w'" >"$tmp/w_out.txt" 2>"$tmp/w_err.txt"
rc=$?
check "write cut short: exit 1 (status $rc)" [ $rc -eq 1 ]
check "write cut short: the message names the cause ($(tail -n 1 "$tmp/w_err.txt"))" grep -q 'File too large' "$tmp/w_err.txt"
check "write cut short: only the old w_base.obj is left, unchanged ($(ls "$tmp" | grep '^w_' | tr '\n' ' '))" \
  sh -c "[ \"\$(ls '$tmp' | grep '^w_' | grep -v -e '_out.txt' -e '_err.txt')\" = w_base.obj ] && [ \"\$(cat '$tmp/w_base.obj')\" = old ]"

found=0
for d in /usr/share/assimp/models /usr/share/assimp-testmodels; do
  for f in OFF/invalid.off OBJ/number_formats.obj OBJ/box_UTF16BE.obj OBJ/testline.obj; do
    if [ -f "$d/$f" ]; then refuse "assimp-testmodels $f" 1 "$d/$f" -o "$tmp/x"; found=$((found + 1)); fi
  done
  [ $found -gt 0 ] && break
done
[ $found -eq 0 ] && { echo "SKIP malformed files of assimp-testmodels: not installed (apt-get install assimp-testmodels)"; skip=$((skip + 4)); }

echo "TESTCOUNT dispmesh_smoke passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
