#!/bin/sh
# dispmesh_meshes.sh BUILD_DIR - issue 16's test over many meshes: build/dispmesh (paper 000 end to end,
# the fallback on where the shell is too thin) on generated and real meshes, each at 500 faces with a
# 512^2 map and at 2000 faces with a 1024^2 map. Every run must:
#   exit 0 with a RESULT line; faces <= 1.02 x the target (or the input's count when it has fewer);
#   flagged (texels under the base without a hit) <= 0.01; the fallback's share of the original's area
#   0 on the generated sphere and brick, <= 0.2 on every other mesh;
# and meet issue 16's quality criteria:
#   rms <= 0.1 x base_only_rms; max <= 0.25 x base_only_max; base_only_rms <= 2.2 x unconstrained_rms.
# The criteria that runs do not meet yet are listed below (KNOWN, per run and criterion) and counted
# as skipped; a known miss that is met says so (take it off the list). Every other criterion is
# asserted. Meshes: the generated brick, sphere (bench/gen_sphere.c), three parts with a thin limb and an
# open patch (tests/gen_shapes.c); the bunny (glmark2-data); the elephant, triceratops, cow, fandisk and
# camel of CGAL's data set (libcgal-demo), and its blobby-shuffled (half of its triangles turned the
# other way: build/dispmesh orients it with dm_orient). A missing package skips its meshes (counted).
# Under TEST_SANITIZE=1 only the generated meshes at 500 faces run (the rest take minutes there).
B="$1"
top=$(cd "$(dirname "$0")/.." && pwd)
pass=0; fail=0; skip=0
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
num() { awk "BEGIN { exit !($*) }" 2>/dev/null; }
field() { echo "$2" | tr ' ' '\n' | sed -n "s/^$1=//p" | head -n 1; }

# the criteria that runs miss today (issue 16 is open): mesh:faces:criterion, each counted as skipped
KNOWN="triceratops:500:max cow:500:max fandisk:500:rms fandisk:500:max \
fandisk:2000:max camel:500:max"

if [ "${TEST_SANITIZE:-0}" = 1 ]; then
  make -s -C "$top" --no-print-directory B="$B" OPT="-O1 -g" \
    XFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" \
    "$B/dispmesh" "$B/gen_sphere" "$B/gen_shapes" >&2
else
  make -s -C "$top" --no-print-directory B="$B" "$B/dispmesh" "$B/gen_sphere" "$B/gen_shapes" >&2
fi
for p in dispmesh gen_sphere gen_shapes; do
  if [ ! -x "$B/$p" ]; then
    echo "FAIL $B/$p could not be built"
    echo "TESTCOUNT dispmesh_meshes passed=0 failed=1 skipped=0"
    exit 1
  fi
done
case "$B" in /*) ;; *) B="$top/$B" ;; esac
tmp=$(mktemp -d "${TMPDIR:-/tmp}/dispmesh_meshes.XXXXXX") || { echo "FAIL mktemp"; exit 1; }
trap 'rm -rf "$tmp"' EXIT

"$B/gen_sphere" -f 24 -o "$tmp/sphere.off" >/dev/null || bad "gen_sphere"
"$B/gen_shapes" parts "$tmp/parts.off" || bad "gen_shapes parts"
"$B/gen_shapes" open "$tmp/open.off" || bad "gen_shapes open"
set -- brick "$tmp/sphere.off" "$tmp/parts.off" "$tmp/open.off"
if [ "${TEST_SANITIZE:-0}" != 1 ]; then
  if [ -f /usr/share/glmark2/models/bunny.obj ]; then
    set -- "$@" /usr/share/glmark2/models/bunny.obj
  else
    echo "SKIP bunny: needs glmark2-data (apt-get install glmark2-data)"; skip=$((skip + 1))
  fi
  data=/usr/share/doc/libcgal-dev/data.tar.gz
  if [ -f "$data" ]; then
    for m in elephant triceratops cow fandisk camel blobby-shuffled; do
      tar xzf "$data" -O "data/meshes/$m.off" >"$tmp/$m.off" 2>/dev/null && [ -s "$tmp/$m.off" ] &&
        set -- "$@" "$tmp/$m.off"
    done
  else
    echo "SKIP CGAL's meshes: need libcgal-demo (apt-get install libcgal-demo)"; skip=$((skip + 6))
  fi
fi

for m in "$@"; do
  if [ "$m" = brick ]; then name=brick; in="--brick"; else name=$(basename "$m" | sed 's/\.[^.]*$//'); in="$m"; fi
  for cfg in "500 512" "2000 1024"; do
    set -- $cfg
    target=$1; res=$2
    [ "$name" = brick ] && target=48 # the brick has 496 triangles
    [ "${TEST_SANITIZE:-0}" = 1 ] && [ "$1" = 2000 ] && continue
    run="$name at $target faces, ${res}^2"
    out=$("$B/dispmesh" $in --faces "$target" --res "$res" --no-views -o "$tmp/run" 2>"$tmp/err")
    rc=$?
    line=$(echo "$out" | grep '^RESULT dispmesh ' | tail -n 1)
    if [ $rc -ne 0 ] || [ -z "$line" ]; then
      bad "$run: exit $rc, no RESULT line"; tail -n 3 "$tmp/err" | sed 's/^/    /'; continue
    fi
    faces=$(field faces "$line"); fb=$(field fallback "$line"); flagged=$(field flagged "$line")
    rms=$(field rms "$line"); mx=$(field max "$line"); brms=$(field base_only_rms "$line")
    bmax=$(field base_only_max "$line"); urms=$(field unconstrained_rms "$line")
    input=$(sed -n 's/.*simplify (shell-constrained).* \([0-9][0-9]*\) -> [0-9]* triangles.*/\1/p' "$tmp/err" | tail -n 1)
    want=$target; [ -n "$input" ] && [ "$input" -lt "$target" ] && want=$input
    echo "  values $run: faces=$faces fallback=$fb flagged=$flagged rms/base=$(awk "BEGIN{printf \"%.3f\", $rms/$brms}") max/base=$(awk "BEGIN{printf \"%.3f\", $mx/$bmax}") base/unconstrained=$(awk "BEGIN{printf \"%.2f\", $brms/$urms}")"
    if num "$faces <= 1.02 * $want"; then pass=$((pass + 1)); else bad "$run: $faces faces for a target of $want"; fi
    if num "$flagged <= 0.01"; then pass=$((pass + 1)); else bad "$run: flagged $flagged > 0.01"; fi
    limit=0.2; case "$name" in brick|sphere) limit=0 ;; esac
    if num "$fb <= $limit"; then pass=$((pass + 1)); else bad "$run: fallback $fb > $limit"; fi
    for crit in rms max base_only; do
      case $crit in
        rms) num "$rms <= 0.1 * $brms"; met=$? ;;
        max) num "$mx <= 0.25 * $bmax"; met=$? ;;
        base_only) num "$brms <= 2.2 * $urms"; met=$? ;;
      esac
      case " $KNOWN " in
        *" $name:$target:$crit "*)
          if [ $met -ne 0 ]; then
            echo "  note $run: known miss (issue 16): $crit"; skip=$((skip + 1))
          else
            echo "  note $run: now meets $crit: take $name:$target:$crit off KNOWN"; pass=$((pass + 1))
          fi ;;
        *)
          if [ $met -eq 0 ]; then pass=$((pass + 1)); else bad "$run: misses $crit"; fi ;;
      esac
    done
  done
done
echo "TESTCOUNT dispmesh_meshes passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
