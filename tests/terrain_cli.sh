#!/bin/sh
# terrain_cli.sh BUILD_DIR - examples/terrain.c behaves as a tool (issue 21, point 5) and its
# renders are smooth (point 6), with the conventions tests/tools_cli.sh checks for meshconv and
# render_mesh:
#   --help (exit 0) lists every option and says each default; --version (exit 0) prints a line;
#   bad arguments (unknown option, missing value, malformed or out-of-range number: --omega nan,
#   --size 10xabc, --levels abc, --levels 4294967297, a bad preset or shading name, -o x.jpg,
#   --obj x.ply) exit 2 with a message that names the bad argument, and create no output;
#   failures exit 1 with their cause: a divergent --omega (refused at once by the triangle
#   bound, SD4_ERR_TOO_LARGE), --max-triangles below the mesh, an output directory that does not
#   exist, a write cut short by the file-size limit (ulimit -f with SIGXFSZ ignored, so write()
#   fails with EFBIG as on a full disk), an --obj that cannot be written: afterwards neither
#   OUTPUT nor OUTPUT.tmp exists (the PNG is not left behind when the OBJ fails), and an OUTPUT
#   that existed before is unchanged; a good run writes a PNG (signature checked, also for a .PNG
#   name) and the OBJ with the counts it reports, and leaves no .tmp;
#   smooth shading (the default) vs --shading flat on a terrain whose quads are ~6 px wide: the
#   mean squared difference between horizontally adjacent terrain pixels is less than half the
#   flat render's (flat quads are blocks with steps at their edges; smooth ones ramp across;
#   pixels read back by test_render --png-msd, with render.h's PNG reader).
# The binaries are built here with make (with the sanitizer flags of `make sanitize` when
# TEST_SANITIZE=1; the sizes are small).
B="$1"
top=$(cd "$(dirname "$0")/.." && pwd)
pass=0; fail=0; skip=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
check() { # check DESCRIPTION CONDITION-COMMAND...
  what="$1"; shift
  if "$@"; then ok; else bad "$what"; fi
}
LC_ALL=C; export LC_ALL

if [ "${TEST_SANITIZE:-0}" = 1 ]; then
  make -s -C "$top" --no-print-directory B="$B" OPT="-O1 -g" \
    XFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" "$B/terrain" "$B/test_render" >&2
else
  make -s -C "$top" --no-print-directory B="$B" "$B/terrain" "$B/test_render" >&2
fi
if [ $? -ne 0 ] || [ ! -x "$B/terrain" ] || [ ! -x "$B/test_render" ]; then
  echo "FAIL $B/terrain or $B/test_render could not be built (make $B/terrain $B/test_render)"
  echo "TESTCOUNT terrain_cli passed=0 failed=1 skipped=0"
  exit 1
fi
case "$B" in /*) bin="$B" ;; *) bin="$top/$B" ;; esac
TR="$bin/terrain"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/terrain_cli.XXXXXX") || { echo "FAIL mktemp"; exit 1; }
trap 'rm -rf "$tmp"' EXIT

# run NAME PROGRAM ARGS...: status in $rc, stdout in $tmp/NAME.out, stderr in $tmp/NAME.err
run() {
  run_name="$1"; shift
  "$@" >"$tmp/$run_name.out" 2>"$tmp/$run_name.err"
  rc=$?
  if grep -q -E 'Sanitizer|runtime error' "$tmp/$run_name.err"; then bad "$run_name: sanitizer report"; cat "$tmp/$run_name.err"; fi
}
# refuse NAME STATUS WORD PROGRAM ARGS...: exits STATUS, stderr names WORD, no $tmp/o* file appears
refuse() {
  rname="$1"; want="$2"; word="$3"; shift 3
  rm -f "$tmp"/o*
  run "$rname" "$@"
  check "$rname: exit $want (got $rc: $(cat "$tmp/$rname.err"))" [ "$rc" -eq "$want" ]
  check "$rname: the message names '$word' ($(cat "$tmp/$rname.err"))" grep -q -F -e "$word" "$tmp/$rname.err"
  check "$rname: no output file left ($(ls "$tmp" | grep '^o' | tr '\n' ' '))" sh -c "! ls '$tmp' | grep -q '^o'"
}
# a small, quick terrain: 2 levels (33 x 33 points), no epsilon split
small="--preset mountain6 --levels 2 --eps 0 --size 96x72"

# ---- --help and --version -------------------------------------------------------------------------
run help "$TR" --help
check "terrain --help exits 0" [ "$rc" -eq 0 ]
for o in --preset -o --output --size --seed --levels --omega --omega-half --eps --sigma --cubic --max-triangles \
         --shading --obj --help --version; do
  check "terrain --help lists $o" grep -q -e " $o" "$tmp/help.out"
done
# every option's entry (its line and the indented lines under it) says its default, or that it is
# required; --help and --version excepted
nodefault=$(awk '/^  -/ { if (opt != "" && !seen) printf "%s ", opt; opt = $1; seen = 0 }
                 /default|required/ { seen = 1 }
                 /^[^ ]/ { if (opt != "" && !seen) printf "%s ", opt; opt = "" }
                 END { if (opt != "" && !seen) printf "%s ", opt }' "$tmp/help.out" | sed 's/-h, //; s/--version //')
check "terrain --help gives every option's default (none for: $nodefault)" test -z "$(echo "$nodefault" | sed 's/-h,//; s/ //g')"
run version "$TR" --version
check "terrain --version exits 0 with a line naming terrain" sh -c "[ $rc -eq 0 ] && grep -q '^terrain ' '$tmp/version.out'"

# ---- usage errors (2) ------------------------------------------------------------------------------
refuse none 2 "--preset" "$TR"
refuse no-o 2 "-o" "$TR" --preset desert
refuse unknown 2 "--bogus" "$TR" $small -o "$tmp/out.png" --bogus
refuse stray 2 "'stray'" "$TR" $small -o "$tmp/out.png" stray
refuse preset 2 "--preset 'moon'" "$TR" --preset moon -o "$tmp/out.png"
refuse jpg 2 "out.jpg" "$TR" $small -o "$tmp/out.jpg"
refuse x-obj-ext 2 "out.ply" "$TR" $small -o "$tmp/out.png" --obj "$tmp/out.ply"
refuse shading 2 "--shading 'toon'" "$TR" $small -o "$tmp/out.png" --shading toon
refuse size-missing 2 "--size needs a value" "$TR" $small -o "$tmp/out.png" --size
for v in nan inf -nan 1e999 0.5x '' 3; do
  refuse "w[$v]" 2 "--omega '$v'" "$TR" $small -o "$tmp/out.png" --omega "$v"
done
for v in 10xabc 0 16385 4294967297 10x x10 ' 10'; do
  refuse "size[$v]" 2 "--size '$v'" "$TR" $small -o "$tmp/out.png" --size "$v"
done
for v in abc 4294967297 11 -1 2.5 ''; do
  refuse "levels[$v]" 2 "--levels '$v'" "$TR" $small -o "$tmp/out.png" --levels "$v"
done
for spec in "--seed -1" "--seed 4294967297" "--eps nan" "--eps -1" "--sigma abc" "--sigma 1e400" "--max-triangles 0"; do
  set -- $spec
  refuse "num[$1 $2]" 2 "$1 '$2'" "$TR" $small -o "$tmp/out.png" "$1" "$2"
done

# ---- failures (1) ----------------------------------------------------------------------------------
# a divergent w: epsilon refinement would never stop; the triangle bound refuses it before building
start=$(date +%s)
refuse divergent 1 "SD4_ERR_TOO_LARGE" "$TR" --preset mountain6 --omega 0.5 -o "$tmp/out.png"
check "divergent: refused within 10 s (took $(($(date +%s) - start)) s)" test $(($(date +%s) - start)) -le 10
check "divergent: the message says what to change ($(cat "$tmp/divergent.err"))" grep -q -e "--omega" "$tmp/divergent.err"
refuse max-tri 1 "--max-triangles 1000" "$TR" $small -o "$tmp/out.png" --max-triangles 1000
refuse no-dir 1 "No such file or directory" "$TR" $small -o "$tmp/nodir/out.png"
check "no-dir: nothing created in the missing directory" [ ! -e "$tmp/nodir" ]
refuse x-obj-no-dir 1 "No such file or directory" "$TR" $small -o "$tmp/out.png" --obj "$tmp/nodir/out.obj"
# a write cut short: 2 blocks of file size (1 KiB in dash, 2 KiB in bash) against a 256x192 PNG of ~100 KB
refuse efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$TR' --preset mountain6 --levels 2 --eps 0 --size 256x192 -o '$tmp/out.png'"
refuse efbig-obj 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$TR' $small -o '$tmp/out.png' --obj '$tmp/out.obj'"
printf 'old\n' >"$tmp/keep.png"
run keep sh -c "ulimit -f 2; trap '' XFSZ; exec '$TR' --preset mountain6 --levels 2 --eps 0 --size 256x192 -o '$tmp/keep.png'"
check "keep: exit 1 (got $rc)" [ "$rc" -eq 1 ]
check "keep: the existing output is unchanged and no .tmp is left" sh -c "[ \"\$(cat '$tmp/keep.png')\" = old ] && [ ! -e '$tmp/keep.png.tmp' ]"
mkdir "$tmp/odir.png"
run dir "$TR" $small -o "$tmp/odir.png"
check "dir: an output that is a directory: exit 1 naming the cause ($(cat "$tmp/dir.err"))" \
  sh -c "[ $rc -eq 1 ] && grep -q 'cannot rename' '$tmp/dir.err' && [ ! -e '$tmp/odir.png.tmp' ]"
rmdir "$tmp/odir.png"

# ---- good runs -------------------------------------------------------------------------------------
for name in good.png good2.PNG; do
  run "ok-$name" "$TR" $small -o "$tmp/$name" --obj "$tmp/$name.obj"
  check "terrain -o $name exits 0 ($(cat "$tmp/ok-$name.err"))" [ "$rc" -eq 0 ]
  check "$name begins with the PNG signature and no .tmp is left" \
    sh -c "[ \"\$(od -An -tx1 -N8 '$tmp/$name' | tr -d ' \n')\" = 89504e470d0a1a0a ] && [ ! -e '$tmp/$name.tmp' ] && [ ! -e '$tmp/$name.obj.tmp' ]"
  nv=$(grep -c '^v ' "$tmp/$name.obj"); nt=$(grep -c '^f ' "$tmp/$name.obj")
  check "$name.obj has the reported counts ($nv vertices, $nt triangles; $(cat "$tmp/ok-$name.err"))" \
    grep -q ": $nv vertices, $nt triangles" "$tmp/ok-$name.err"
done
check "33 x 33 points, 2048 triangles at 2 levels without a split ($nv, $nt)" test "$nv" = 1089 -a "$nt" = 2048

# ---- smooth vs flat shading ------------------------------------------------------------------------
# msd PNG: the mean squared difference (0..255 units, summed over RGB) between horizontally adjacent
# pixels that both differ from the sky (the corner pixel), and the number of such pairs
msd() { "$bin/test_render" --png-msd "$1"; }
look="--preset mountain5 --levels 3 --eps 0 --size 400x300"
run smooth "$TR" $look -o "$tmp/smooth.png"
rc_smooth=$rc
run flat "$TR" $look -o "$tmp/flat.png" --shading flat
check "smooth and flat renders exit 0 ($(cat "$tmp/smooth.err" "$tmp/flat.err"))" test "$rc_smooth" -eq 0 -a "$rc" -eq 0
set -- $(msd "$tmp/smooth.png") $(msd "$tmp/flat.png")
echo "terrain 400x300, 64 x 64 quads: adjacent-pixel mean squared difference smooth $1 ($2 pairs), flat $3 ($4 pairs)"
check "both renders show the terrain (>= 20000 pixel pairs: $2, $4)" test "${2:-0}" -ge 20000 -a "${4:-0}" -ge 20000
check "smooth shading: adjacent pixels differ less than half as much as flat's blocks ($1 vs $3)" test $((${1:-0} * 2)) -lt "${3:-0}"

echo "TESTCOUNT terrain_cli passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
