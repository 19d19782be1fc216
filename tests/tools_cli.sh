#!/bin/sh
# tools_cli.sh BUILD_DIR - examples/meshconv.c and examples/render_mesh.c behave as tools (issue 21, point 5):
#   --help (exit 0) names every option and its default; --version (exit 0) prints a line;
#   bad arguments (unknown option, missing value, malformed or out-of-range number, nan, a bad name,
#   an output extension the program does not write such as -o x.jpg) exit 2 with a message that
#   names the bad argument, and create no output;
#   failures exit 1 with their cause: a missing input (the system's reason), malformed input (meshio's
#   result name and meaning), an output directory that does not exist, and a write cut short by the
#   file-size limit (ulimit -f with SIGXFSZ ignored, so write() fails with EFBIG as on a full disk):
#   afterwards neither OUTPUT nor OUTPUT.tmp exists, and an OUTPUT that existed before is unchanged;
#   meshconv round trips a 30x30 grid through .OBJ .Off .ply .STL (binary and --ascii) with the same
#   counts and bounding box (STL: 3 vertices per triangle, --weld gives the grid's count back), and a
#   cube's 12-facet STL soup welds to 8 vertices; render_mesh writes a PNG (signature checked), also
#   for a .PNG name, and leaves no .tmp; its view is fitted and turns with --up (a 1x1x10 bar seen
#   from the front: y up shows the square end, z up the bar upright, x up the bar across, each
#   filling >= 85% of the image side with a border; triangles 6e38 and 6e-30 wide draw the same
#   pixel box as a unit one; pixels read back with python3, skipped without).
# The other programs (dispmesh, deform, relief, grass, gen_sphere; dispmesh's long runs are in
# dispmesh_smoke.sh) the same way: --help names each option, --version; bad arguments (nan,
# 4294967297, 10xabc, a bad name, an unknown option, a missing value, -o x.jpg) exit 2 naming them
# with no output; a missing or malformed input exits 1 with its cause; a write cut short by
# ulimit -f exits 1 with "File too large" and leaves no output and no .tmp (relief: its 11 KB
# render passes the limit and its 37 KB --height does not, and neither is left; an OUT that
# existed is unchanged); a small good run exits 0 with its files and no .tmp.
# The binaries are built here with make (with the sanitizer flags of `make sanitize` when
# TEST_SANITIZE=1; the sizes are small enough that nothing needs shrinking).
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

for p in meshconv render_mesh dispmesh deform relief grass gen_sphere; do
  if [ "${TEST_SANITIZE:-0}" = 1 ]; then
    make -s -C "$top" --no-print-directory B="$B" OPT="-O1 -g" \
      XFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" "$B/$p" >&2
  else
    make -s -C "$top" --no-print-directory B="$B" "$B/$p" >&2
  fi
  if [ $? -ne 0 ] || [ ! -x "$B/$p" ]; then
    echo "FAIL $B/$p could not be built (make $B/$p)"
    echo "TESTCOUNT tools_cli passed=0 failed=1 skipped=0"
    exit 1
  fi
done
case "$B" in /*) bin="$B" ;; *) bin="$top/$B" ;; esac
MC="$bin/meshconv"; RM="$bin/render_mesh"
DM="$bin/dispmesh"; DF="$bin/deform"; RL="$bin/relief"; GR="$bin/grass"; GS="$bin/gen_sphere"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/tools_cli.XXXXXX") || { echo "FAIL mktemp"; exit 1; }
trap 'rm -rf "$tmp"' EXIT

# ---- inputs ---------------------------------------------------------------------------------------
awk 'BEGIN { n = 30; for (j = 0; j < n; j++) for (i = 0; i < n; i++) printf "v %.4f %.4f %.4f\n", i / 7.0, j / 11.0, (i * j) % 5 / 3.0;
             for (j = 0; j < n - 1; j++) for (i = 0; i < n - 1; i++) { a = j * n + i + 1; printf "f %d %d %d\nf %d %d %d\n", a, a + 1, a + n + 1, a, a + n + 1, a + n } }' \
  >"$tmp/grid.obj"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n%s\n' \
  'f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8' >"$tmp/cube.obj"
printf 'v 0 0 0\nv 1 0 0\nf 1 2 7\n' >"$tmp/bad.obj"

# run NAME PROGRAM ARGS...: status in $rc, stdout in $tmp/NAME.out, stderr in $tmp/NAME.err
run() {
  run_name="$1"; shift
  "$@" >"$tmp/$run_name.out" 2>"$tmp/$run_name.err"
  rc=$?
  if grep -q -E 'Sanitizer|runtime error' "$tmp/$run_name.err"; then bad "$run_name: sanitizer report"; cat "$tmp/$run_name.err"; fi
}
field() { # field NAME KEY: the value of KEY= in the RESULT line of run NAME
  grep '^RESULT meshconv ' "$tmp/$1.out" | tr ' ' '\n' | sed -n "s/^$2=//p"
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

# ---- --help and --version -------------------------------------------------------------------------
for p in meshconv render_mesh dispmesh deform relief grass gen_sphere; do
  prog="$bin/$p"
  run "$p-help" "$prog" --help
  check "$p --help exits 0" [ "$rc" -eq 0 ]
  check "$p --help says default" grep -q default "$tmp/$p-help.out"
  run "$p-version" "$prog" --version
  check "$p --version exits 0 with a line naming $p" sh -c "[ $rc -eq 0 ] && grep -q '^$p ' '$tmp/$p-version.out'"
done
for o in -o --output --ascii --weld --format --help --version; do
  check "meshconv --help lists $o" grep -q -e " $o" "$tmp/meshconv-help.out"
done
for o in -o --output --view --up --wire --size --shading --ortho --help --version; do
  check "render_mesh --help lists $o" grep -q -e " $o" "$tmp/render_mesh-help.out"
done
for o in --brick -o --output --faces --res --size --no-views --both-ways --strict --min-quality --samples --help --version; do
  check "dispmesh --help lists $o" grep -q -e " $o" "$tmp/dispmesh-help.out"
done
for o in --cylinder --box -o --output --case --angle --shift --up --region --roi --handle --method --weights --frames \
         --ortho --soft --rigid --steps --obj --size --help --version; do
  check "deform --help lists $o" grep -q -e " $o" "$tmp/deform-help.out"
done
for o in -o --output --crop --size --white --emboss --patch --emphasis --depth --frame --light --no-shadows --cylinder \
         --height --normal --sheet --help --version; do
  check "relief --help lists $o" grep -q -e " $o" "$tmp/relief-help.out"
done
for o in --scene -o --output --size --res --tiles --mesh --mesh-cells --wd --wd-sun --wd-map --wd-map-gain --lod-bias \
         --frames --seed --quiet --help --version; do
  check "grass --help lists $o" grep -q -e " $o" "$tmp/grass-help.out"
done
for o in -f -o --output --help --version; do
  check "gen_sphere --help lists $o" grep -q -e " $o" "$tmp/gen_sphere-help.out"
done

# ---- meshconv: usage errors (2) and failures (1) ---------------------------------------------------
refuse mc-none 2 INPUT "$MC"
refuse mc-unknown 2 --bogus "$MC" "$tmp/grid.obj" --bogus
refuse mc-format 2 xyz "$MC" "$tmp/grid.obj" --format xyz
refuse mc-o-missing 2 -o "$MC" "$tmp/grid.obj" -o
refuse mc-two-inputs 2 "$tmp/cube.obj" "$MC" "$tmp/grid.obj" "$tmp/cube.obj"
refuse mc-jpg 2 out.jpg "$MC" "$tmp/grid.obj" -o "$tmp/out.jpg"
refuse mc-noext 2 out "$MC" "$tmp/grid.obj" -o "$tmp/out"
refuse mc-missing-input 1 "No such file or directory" "$MC" "$tmp/missing.obj" -o "$tmp/out.obj"
refuse mc-bad-input 1 "MIO_ERR_INDEX_RANGE: a face refers to a vertex that does not exist" "$MC" "$tmp/bad.obj" -o "$tmp/out.obj"
refuse mc-no-dir 1 "No such file or directory" "$MC" "$tmp/grid.obj" -o "$tmp/nodir/out.obj"
check "mc-no-dir: nothing created in the missing directory" [ ! -e "$tmp/nodir" ]
# a write cut short: 2 blocks of file size (1 KiB in dash, 2 KiB in bash) against about 40 KB of text
refuse mc-efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$MC' '$tmp/grid.obj' -o '$tmp/out.ply' --ascii"
printf 'old\n' >"$tmp/keep.obj"
run mc-keep sh -c "ulimit -f 2; trap '' XFSZ; exec '$MC' '$tmp/grid.obj' -o '$tmp/keep.obj'"
check "mc-keep: exit 1 (got $rc)" [ "$rc" -eq 1 ]
check "mc-keep: the existing output is unchanged and no .tmp is left" sh -c "[ \"\$(cat '$tmp/keep.obj')\" = old ] && [ ! -e '$tmp/keep.obj.tmp' ]"

mkdir "$tmp/odir.obj"
run mc-dir "$MC" "$tmp/grid.obj" -o "$tmp/odir.obj"
check "mc-dir: an output that is a directory: exit 1 naming the cause ($(cat "$tmp/mc-dir.err"))" \
  sh -c "[ $rc -eq 1 ] && grep -q 'cannot rename' '$tmp/mc-dir.err' && [ ! -e '$tmp/odir.obj.tmp' ]"
rmdir "$tmp/odir.obj"
cp "$tmp/cube.obj" "$tmp/same.obj"
run mc-same "$MC" "$tmp/same.obj" -o "$tmp/same.obj"
run mc-same-r "$MC" "$tmp/same.obj"
check "mc-same: input and output the same file: exit 0 and the file reads as the cube ($(cat "$tmp/mc-same.err"))" \
  test "$rc" -eq 0 -a "$(field mc-same-r vertices)" = 8 -a "$(field mc-same-r triangles)" = 12

# ---- meshconv: round trips -------------------------------------------------------------------------
run mc-grid "$MC" "$tmp/grid.obj"
V=$(field mc-grid vertices); T=$(field mc-grid triangles); BOX=$(field mc-grid bbox)
check "grid reads as 900 vertices, 1682 triangles (got $V, $T)" test "$V" = 900 -a "$T" = 1682
i=0
for spec in "g.OBJ" "g.Off" "g.ply" "g.PLY --ascii" "g.STL" "g.Stl --ascii"; do
  i=$((i + 1))
  set -- $spec
  name="mc-rt$i"
  run "$name-w" "$MC" "$tmp/grid.obj" -o "$tmp/$1" $2
  check "$name: meshconv grid.obj -o $spec exits 0 ($(cat "$tmp/$name-w.err"))" [ "$rc" -eq 0 ]
  check "$name: $1 exists and no .tmp is left" sh -c "[ -s '$tmp/$1' ] && [ ! -e '$tmp/$1.tmp' ]"
  run "$name-r" "$MC" "$tmp/$1"
  case "$1" in *.STL|*.Stl) wantv=$((3 * T)) ;; *) wantv=$V ;; esac
  check "$name: $1 reads back with $wantv vertices, $T triangles, bbox $BOX (got $(field "$name-r" vertices), $(field "$name-r" triangles), $(field "$name-r" bbox))" \
    test "$(field "$name-r" vertices)" = "$wantv" -a "$(field "$name-r" triangles)" = "$T" -a "$(field "$name-r" bbox)" = "$BOX"
  run "$name-weld" "$MC" "$tmp/$1" --weld
  check "$name: $1 --weld gives $V vertices (got $(field "$name-weld" vertices))" [ "$(field "$name-weld" vertices)" = "$V" ]
done
run mc-cube-stl "$MC" "$tmp/cube.obj" -o "$tmp/cube.stl"
run mc-cube-soup "$MC" "$tmp/cube.stl"
check "cube STL soup has 36 vertices (got $(field mc-cube-soup vertices))" [ "$(field mc-cube-soup vertices)" = 36 ]
run mc-cube-weld "$MC" "$tmp/cube.stl" --weld -o "$tmp/cube_welded.off"
check "cube STL --weld gives 8 vertices, 12 triangles (got $(field mc-cube-weld vertices), $(field mc-cube-weld triangles))" \
  test "$(field mc-cube-weld vertices)" = 8 -a "$(field mc-cube-weld triangles)" = 12
check "welded cube written as OFF with 8 vertices" sh -c "sed -n 2p '$tmp/cube_welded.off' | grep -q '^8 12 0\$'"

# ---- render_mesh -----------------------------------------------------------------------------------
refuse rm-none 2 "no input" "$RM"
refuse rm-no-o 2 "-o" "$RM" "$tmp/grid.obj"
refuse rm-unknown 2 --bogus "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --bogus
refuse rm-jpg 2 out.jpg "$RM" "$tmp/grid.obj" -o "$tmp/out.jpg"
for s in 10xabc 0 16385 4294967297 -5 10x 'x10' '10x10x10' ' 10'; do
  refuse "rm-size[$s]" 2 "--size '$s'" "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --size "$s"
done
for v in nan,0 0,nan inf,10 0,90 0,-90 1,2x abc 1e40,0 ''; do
  refuse "rm-view[$v]" 2 "--view '$v'" "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --view "$v"
done
refuse rm-up 2 "--up 'w'" "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --up w
refuse rm-shading 2 "--shading 'toon'" "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --shading toon
refuse rm-size-missing 2 "--size needs a value" "$RM" "$tmp/grid.obj" -o "$tmp/out.png" --size
refuse rm-missing-input 1 "No such file or directory" "$RM" "$tmp/missing.obj" -o "$tmp/out.png"
refuse rm-bad-input 1 "MIO_ERR_INDEX_RANGE" "$RM" "$tmp/bad.obj" -o "$tmp/out.png"
refuse rm-no-dir 1 "SR_ERR_IO" "$RM" "$tmp/grid.obj" -o "$tmp/nodir/out.png"
refuse rm-efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$RM' '$tmp/grid.obj' -o '$tmp/out.png' --size 512"
for spec in "out.png 64x48" "out2.PNG 33"; do
  set -- $spec
  run "rm-ok-$1" "$RM" "$tmp/grid.obj" -o "$tmp/$1" --size "$2" --wire --view 20,-30
  check "render_mesh -o $1 --size $2 exits 0 ($(cat "$tmp/rm-ok-$1.err"))" [ "$rc" -eq 0 ]
  check "$1 begins with the PNG signature and no .tmp is left" \
    sh -c "[ \"\$(od -An -tx1 -N8 '$tmp/$1' | tr -d ' \n')\" = 89504e470d0a1a0a ] && [ ! -e '$tmp/$1.tmp' ]"
done

# ---- render_mesh: a fitted view that turns with --up -------------------------------------------------
# bbox PNG: "x0 y0 x1 y1 W H" of the pixels that differ from the corner pixel (the background), read
# with python3's zlib (PNG's five row filters undone here).
bbox() {
  python3 - "$1" <<'PY'
import sys, zlib, struct
d = open(sys.argv[1], 'rb').read()
assert d[:8] == b'\x89PNG\r\n\x1a\n'
pos, idat, w = 8, b'', 0
while pos < len(d):
    n, t = struct.unpack('>I4s', d[pos:pos + 8]); body = d[pos + 8:pos + 8 + n]; pos += 12 + n
    if t == b'IHDR': w, h, depth, ctype = struct.unpack('>IIBB', body[:10])
    if t == b'IDAT': idat += body
bpp = {2: 3, 6: 4}[ctype]; raw = zlib.decompress(idat); stride = w * bpp
rows, prev, i = [], bytearray(stride), 0
for y in range(h):
    f = raw[i]; line = bytearray(raw[i + 1:i + 1 + stride]); i += 1 + stride
    for x in range(stride):
        a = line[x - bpp] if x >= bpp else 0; b = prev[x]; c = prev[x - bpp] if x >= bpp else 0
        if f == 1: line[x] = (line[x] + a) & 255
        elif f == 2: line[x] = (line[x] + b) & 255
        elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line); prev = line
bg = rows[0][0:3]; x0, y0, x1, y1 = w, h, -1, -1
for y in range(h):
    for x in range(w):
        if sum(abs(rows[y][x * bpp + k] - bg[k]) for k in range(3)) > 24:
            x0, y0, x1, y1 = min(x0, x), min(y0, y), max(x1, x), max(y1, y)
print(x0, y0, x1, y1, w, h)
PY
}
if command -v python3 >/dev/null 2>&1; then
  # a bar 10 long in z: front with y up sees its 1x1 end; z up turns it upright; x up lays it across
  printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 10\nv 1 0 10\nv 1 1 10\nv 0 1 10\n%s\n' "$(sed -n '/^f/p' "$tmp/cube.obj")" >"$tmp/bar.obj"
  for spec in "y persp" "z persp" "x persp" "z ortho" "x ortho"; do
    set -- $spec
    extra=""; [ "$2" = ortho ] && extra=--ortho
    run "rm-up-$1-$2" "$RM" "$tmp/bar.obj" -o "$tmp/up_$1_$2.png" --size 120x100 --view front --shading flat --up "$1" $extra
    check "render_mesh --up $1 ($2) exits 0 ($(cat "$tmp/rm-up-$1-$2.err"))" [ "$rc" -eq 0 ]
    set -- $(bbox "$tmp/up_$1_$2.png") "$1" "$2"
    echo "render_mesh --up $7 ($8) front of a 1x1x10 bar: mesh pixels $1,$2-$3,$4 of $5x$6"
    bw=$(($3 - $1 + 1)); bh=$(($4 - $2 + 1))
    # fitted with a 5% border: the long side fills >= 85% of its image side, and no pixel touches the edge
    check "--up $7 ($8): the mesh inside the frame with a border (box $1,$2-$3,$4 of $5x$6)" \
      test "$1" -ge 1 -a "$2" -ge 1 -a "$3" -le $(($5 - 2)) -a "$4" -le $(($6 - 2))
    case "$7" in
      y) check "--up y front: the bar's 1x1 end fills the height (box ${bw}x$bh of $5x$6)" \
           test $((bh * 100)) -ge $(($6 * 85)) -a $((bw * 2)) -ge "$bh" -a $((bh * 2)) -ge "$bw" ;;
      z) check "--up z front: the bar stands upright, filling the height (box ${bw}x$bh of $5x$6)" \
           test $((bh * 100)) -ge $(($6 * 85)) -a "$bh" -ge $((5 * bw)) ;;
      x) check "--up x front: the bar lies across, filling the width (box ${bw}x$bh of $5x$6)" \
           test $((bw * 100)) -ge $(($5 * 85)) -a "$bw" -ge $((5 * bh)) ;;
    esac
  done
  # any finite size renders: a triangle 6e38 wide and one 3e-30 wide fill the frame like a unit one
  for sz in 3e38 3e-30 1; do
    printf 'v -%s 0 0\nv %s 0 0\nv 0 %s 0\nf 1 2 3\n' $sz $sz $sz >"$tmp/tri_$sz.obj"
    run "rm-tri-$sz" "$RM" "$tmp/tri_$sz.obj" -o "$tmp/tri_$sz.png" --size 64 --view front
    check "render_mesh of a triangle of size $sz exits 0" [ "$rc" -eq 0 ]
    box=$(bbox "$tmp/tri_$sz.png")
    [ $sz = 1 ] && unit_box="$box"
    set -- $box
    check "triangle of size $sz: drawn, filling >= 85% of the width (box $box)" test "$3" -ge 0 -a $((($3 - $1 + 1) * 100)) -ge $((64 * 85))
  done
  for sz in 3e38 3e-30; do
    check "triangle of size $sz covers the same pixels box as size 1 ($(bbox "$tmp/tri_$sz.png") vs $unit_box)" test "$(bbox "$tmp/tri_$sz.png")" = "$unit_box"
  done
else
  echo "SKIP render_mesh fitted-view checks: python3 not installed"; skip=$((skip + 23))
fi

# ---- dispmesh, deform, relief, grass, gen_sphere: usage errors (2) -------------------------------------
refuse dm-faces 2 "--faces 'abc'" "$DM" --brick --faces abc -o "$tmp/o"
refuse dm-faces-big 2 "--faces '4294967297'" "$DM" --brick --faces 4294967297 -o "$tmp/o"
refuse dm-minq 2 "--min-quality 'nan'" "$DM" --brick --min-quality nan -o "$tmp/o"
refuse dm-unknown 2 "--bogus" "$DM" --brick --bogus -o "$tmp/o"
refuse dm-missing-value 2 "--res needs a value" "$DM" --brick -o "$tmp/o" --res
refuse dm-none 2 "IN or --brick" "$DM" -o "$tmp/o"
refuse df-angle 2 "--angle 'nan'" "$DF" --cylinder --angle nan -o "$tmp/o.png"
refuse df-angle-trail 2 "--angle '90x'" "$DF" --cylinder --angle 90x -o "$tmp/o.png"
refuse df-steps 2 "--steps '4294967297'" "$DF" --cylinder --steps 4294967297 -o "$tmp/o.png"
refuse df-size 2 "--size '10xabc'" "$DF" --cylinder --size 10xabc -o "$tmp/o.png"
refuse df-case 2 "--case 'foo'" "$DF" --cylinder --case foo -o "$tmp/o.png"
refuse df-unknown 2 "--bogus" "$DF" --cylinder --bogus 1 -o "$tmp/o.png"
refuse df-missing-value 2 "--roi needs a value" "$DF" --cylinder -o "$tmp/o.png" --roi
refuse df-jpg 2 "o.jpg" "$DF" --cylinder -o "$tmp/o.jpg"
refuse df-none 2 "MESH" "$DF" -o "$tmp/o.png"
refuse rl-frame 2 "--frame '10xabc'" "$RL" gen:rock text:R -o "$tmp/o.png" --frame 10xabc
refuse rl-light 2 "--light 'nan,0,1'" "$RL" gen:rock text:R -o "$tmp/o.png" --light nan,0,1
refuse rl-crop 2 "--crop '1,2'" "$RL" gen:rock text:R -o "$tmp/o.png" --crop 1,2
refuse rl-patch 2 "--patch '4294967297'" "$RL" gen:rock text:R -o "$tmp/o.png" --patch 4294967297
refuse rl-unknown 2 "--bogus" "$RL" gen:rock text:R -o "$tmp/o.png" --bogus
refuse rl-jpg 2 "o.jpg" "$RL" gen:rock text:R -o "$tmp/o.jpg"
refuse rl-height-jpg 2 "--height" "$RL" gen:rock text:R -o "$tmp/o.png" --height "$tmp/oh.jpg"
refuse gr-wd 2 "--wd '0.2,nan'" "$GR" --scene wither -o "$tmp/o.png" --wd 0.2,nan
refuse gr-wd-sun 2 "--wd-sun '0.5abc'" "$GR" --mesh sphere -o "$tmp/o.png" --wd-sun 0.5abc
refuse gr-wd-sep 2 "--wd '0.2x0.3'" "$GR" --scene wither -o "$tmp/o.png" --wd 0.2x0.3
refuse gr-size 2 "--size '10xabc'" "$GR" --scene wither -o "$tmp/o.png" --size 10xabc
refuse gr-res 2 "--res '100'" "$GR" --scene wither -o "$tmp/o.png" --res 100
refuse gr-scene 2 "--scene 'foo'" "$GR" --scene foo -o "$tmp/o.png"
refuse gr-seed 2 "--seed '-1'" "$GR" --scene wither -o "$tmp/o.png" --seed -1
refuse gr-unknown 2 "--bogus" "$GR" --scene wither -o "$tmp/o.png" --bogus
refuse gr-jpg 2 "o.jpg" "$GR" --scene wither -o "$tmp/o.jpg"
refuse gr-no-o 2 "-o" "$GR" --scene wither
refuse gs-f 2 "-f 'abc'" "$GS" -f abc -o "$tmp/o.off"
refuse gs-f-big 2 "-f '4294967297'" "$GS" -f 4294967297 -o "$tmp/o.off"
refuse gs-f-zero 2 "-f '0'" "$GS" -f 0 -o "$tmp/o.off"
refuse gs-jpg 2 "o.jpg" "$GS" -f 3 -o "$tmp/o.jpg"
refuse gs-unknown 2 "--bogus" "$GS" --bogus
refuse gs-missing-value 2 "-f needs a value" "$GS" -o "$tmp/o.off" -f

# ---- the same programs: failures (1) with their cause, and writes cut short --------------------------
refuse dm-missing-input 1 "No such file or directory" "$DM" "$tmp/missing.obj" -o "$tmp/odir/o"
check "dm-missing-input: the prefix's directory is not created for a missing input" [ ! -e "$tmp/odir" ]
refuse dm-bad-input 1 "MIO_ERR_INDEX_RANGE" "$DM" "$tmp/bad.obj" -o "$tmp/o"
refuse df-missing-input 1 "No such file or directory" "$DF" "$tmp/missing.obj" -o "$tmp/o.png"
refuse df-bad-input 1 "MIO_ERR_INDEX_RANGE" "$DF" "$tmp/bad.obj" -o "$tmp/o.png"
refuse rl-missing-input 1 "No such file or directory" "$RL" "$tmp/missing.png" text:R -o "$tmp/o.png"
refuse gr-missing-input 1 "No such file or directory" "$GR" --mesh "$tmp/missing.obj" -o "$tmp/o.png"
refuse gr-missing-map 1 "No such file or directory" "$GR" --scene mountain --wd-map "$tmp/missing.png" -o "$tmp/o.png"
refuse gs-no-dir 1 "No such file or directory" "$GS" -f 3 -o "$tmp/nodir/o.off"
refuse df-no-dir 1 "No such file or directory" "$DF" --cylinder --method laplacian --size 32 -o "$tmp/nodir/o.png"
# 2 blocks of file size (1 KiB in dash, 2 KiB in bash); SIGXFSZ ignored so write() fails with EFBIG
refuse gs-efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$GS' -f 30 -o '$tmp/o.off'"
refuse df-efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$DF' --cylinder --method laplacian --size 32 -o '$tmp/o.png' --obj '$tmp/o'"
refuse gr-efbig 1 "File too large" sh -c "ulimit -f 2; trap '' XFSZ; exec '$GR' --scene wither --size 64x48 --res 16 --frames 2 --quiet -o '$tmp/o.png'"
# relief: the 11 KB render passes a 24-block limit (12 KiB in dash, 24 KiB in bash), the 37 KB --height does not
refuse rl-efbig 1 "File too large" sh -c "ulimit -f 24; trap '' XFSZ; exec '$RL' gen:rock text:R --size 96 --frame 120x90 -o '$tmp/o.png' --height '$tmp/oh.pfm'"
printf 'old\n' >"$tmp/keep.png"
run rl-keep sh -c "ulimit -f 24; trap '' XFSZ; exec '$RL' gen:rock text:R --size 96 --frame 120x90 -o '$tmp/keep.png' --height '$tmp/oh.pfm'"
check "rl-keep: exit 1 (got $rc)" [ "$rc" -eq 1 ]
check "rl-keep: the existing output is unchanged and no .tmp is left" \
  sh -c "[ \"\$(cat '$tmp/keep.png')\" = old ] && [ ! -e '$tmp/keep.png.tmp' ] && [ ! -e '$tmp/oh.pfm' ] && [ ! -e '$tmp/oh.pfm.tmp' ]"
printf 'old\n' >"$tmp/keep.off"
run gs-keep sh -c "ulimit -f 2; trap '' XFSZ; exec '$GS' -f 30 -o '$tmp/keep.off'"
check "gs-keep: exit 1 and the existing output unchanged, no .tmp (got $rc)" \
  sh -c "[ $rc -eq 1 ] && [ \"\$(cat '$tmp/keep.off')\" = old ] && [ ! -e '$tmp/keep.off.tmp' ]"

# ---- the same programs: small good runs ------------------------------------------------------------
png_ok() { [ "$(od -An -tx1 -N8 "$1" | tr -d ' \n')" = 89504e470d0a1a0a ] && [ ! -e "$1.tmp" ]; }
run gs-ok "$GS" -f 3 -o "$tmp/g.OFF"
check "gen_sphere -f 3 -o g.OFF: exit 0, 92 vertices, no .tmp ($(cat "$tmp/gs-ok.err"))" \
  sh -c "[ $rc -eq 0 ] && sed -n 2p '$tmp/g.OFF' | grep -q '^92 180 0' && [ ! -e '$tmp/g.OFF.tmp' ]"
run df-ok "$DF" --cylinder --method laplacian --size 32 -o "$tmp/d.png" --obj "$tmp/d"
check "deform --cylinder -o d.png --obj d: exit 0 ($(tail -n 1 "$tmp/df-ok.err"))" [ "$rc" -eq 0 ]
check "deform wrote d.png and d_laplacian.obj, no .tmp" sh -c "[ -s '$tmp/d_laplacian.obj' ] && [ ! -e '$tmp/d_laplacian.obj.tmp' ]"
check "deform's d.png is a PNG" png_ok "$tmp/d.png"
run rl-ok "$RL" gen:rock text:R --size 96 --frame 120x90 -o "$tmp/r.PNG" --height "$tmp/rh.pfm" --normal "$tmp/rn.png"
check "relief -o r.PNG --height --normal: exit 0 ($(tail -n 1 "$tmp/rl-ok.err"))" [ "$rc" -eq 0 ]
check "relief wrote r.PNG, rn.png (PNG) and rh.pfm, no .tmp" sh -c "[ -s '$tmp/rh.pfm' ] && [ ! -e '$tmp/rh.pfm.tmp' ]"
check "relief's r.PNG is a PNG" png_ok "$tmp/r.PNG"
check "relief's rn.png is a PNG" png_ok "$tmp/rn.png"
run gr-ok "$GR" --scene wither --size 32x24 --res 16 --frames 2 --quiet -o "$tmp/w.png"
check "grass --scene wither -o w.png: exit 0 ($(tail -n 1 "$tmp/gr-ok.err"))" [ "$rc" -eq 0 ]
check "grass's w.png is a PNG" png_ok "$tmp/w.png"
# the cube's STL soup (36 corners): dispmesh welds it with mio_weld, as meshconv --weld does
run dm-stl "$DM" "$tmp/cube.stl" --faces 12 --res 64 --no-views -o "$tmp/dcube"
check "dispmesh cube.stl: the soup is welded, 36 -> 8 vertices ($(grep welded "$tmp/dm-stl.err"))" \
  grep -q 'welded vertices at equal positions: 36 -> 8 vertices' "$tmp/dm-stl.err"

# ---- erode (erosion.h, issue 17): usage errors (2), failures (1), a small good run on each domain ----
if [ "${TEST_SANITIZE:-0}" = 1 ]; then
  make -s -C "$top" --no-print-directory B="$B" OPT="-O1 -g" \
    XFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined" "$B/erode" >&2
else
  make -s -C "$top" --no-print-directory B="$B" "$B/erode" >&2
fi
ER="$bin/erode"
if [ -x "$ER" ]; then
  run er-help "$ER" --help
  check "erode --help: exit 0" [ "$rc" -eq 0 ]
  for o in --steps --wind --material --hard --soft --res --faces --height-scale --wrap --rate --render-steps --size --marker -o --torus; do
    check "erode --help lists $o" grep -q -e " $o" "$tmp/er-help.out"
  done
  run er-version "$ER" --version
  check "erode --version: exit 0 and a line" sh -c "[ $rc -eq 0 ] && grep -q '^erode ' '$tmp/er-version.out'"
  # a 32 x 32 PGM height map (P5, maxval 255): a ramp with a ridge
  awk 'BEGIN { printf "P2\n32 32\n255\n"; for (y = 0; y < 32; y++) { for (x = 0; x < 32; x++) printf "%d ", (x * 4 + (x == 16) * 60) % 256; printf "\n" } }' >"$tmp/hm.pgm"
  refuse er-nosteps 2 "--steps" "$ER" "$tmp/hm.pgm" --wind 1,0,-1 -o "$tmp/o1"
  refuse er-steps0 2 "--steps" "$ER" "$tmp/hm.pgm" --steps 0 --wind 1,0,-1 -o "$tmp/o1"
  refuse er-stepsnan 2 "nan" "$ER" "$tmp/hm.pgm" --steps nan --wind 1,0,-1 -o "$tmp/o1"
  refuse er-windzero 2 "zero" "$ER" "$tmp/hm.pgm" --steps 2 --wind 0,0,0 -o "$tmp/o1"
  refuse er-wind2 2 "--wind" "$ER" "$tmp/hm.pgm" --steps 2 --wind 1,0 -o "$tmp/o1"
  refuse er-hard 2 "--hard" "$ER" "$tmp/hm.pgm" --steps 2 --wind 1,0,-1 --hard 4,4 -o "$tmp/o1"
  refuse er-unknown 2 "--bogus" "$ER" "$tmp/hm.pgm" --steps 2 --wind 1,0,-1 --bogus -o "$tmp/o1"
  refuse er-noprefix 2 "-o" "$ER" "$tmp/hm.pgm" --steps 2 --wind 1,0,-1
  refuse er-render 2 "--render-steps" "$ER" "$tmp/hm.pgm" --steps 2 --wind 1,0,-1 --render-steps 3 -o "$tmp/o1"
  refuse er-missing 1 "No such file" "$ER" "$tmp/none.pgm" --steps 2 --wind 1,0,-1 -o "$tmp/o1"
  refuse er-badmesh 1 "bad.obj" "$ER" "$tmp/bad.obj" --steps 2 --wind 1,0,-1 -o "$tmp/o1"
  run er-hf "$ER" "$tmp/hm.pgm" --steps 3 --wind 1,0,-1 --wrap --size 64 -o "$tmp/hf/e"
  check "erode hm.pgm --steps 3: exit 0 ($(tail -n 1 "$tmp/er-hf.err"))" [ "$rc" -eq 0 ]
  check "erode wrote e_map.pfm, e.obj, and PNGs e_map.png (16-bit) and e_render.png, no .tmp" \
    sh -c "[ -s '$tmp/hf/e_map.pfm' ] && [ -s '$tmp/hf/e.obj' ] && ! ls '$tmp/hf' | grep -q tmp"
  check "erode's e_render.png is a PNG" png_ok "$tmp/hf/e_render.png"
  check "erode's e_map.png is a 16-bit grey PNG" sh -c "png_ok() { :; }; [ \"\$(od -An -tx1 -j24 -N2 '$tmp/hf/e_map.png' | tr -d ' \n')\" = 1000 ]"
  check "erode prints RESULT erosion domain=heightfield res=32x32 steps=3" \
    grep -q '^RESULT erosion domain=heightfield res=32x32 steps=3 ' "$tmp/er-hf.out"
  run er-torus "$ER" --torus --steps 2 --wind -1,0,-0.3 --res 64 --size 64 -o "$tmp/tor/t"
  check "erode --torus --res 64 --steps 2: exit 0 ($(tail -n 1 "$tmp/er-torus.err"))" [ "$rc" -eq 0 ]
  check "erode --torus prints RESULT erosion domain=surface with eroded > 0" \
    sh -c "grep '^RESULT erosion domain=surface res=64x64 steps=2 ' '$tmp/er-torus.out' | grep -q -v 'eroded=0 '"
  printf 'old\n' >"$tmp/hf/k_map.pfm"
  run er-keep sh -c "ulimit -f 8; trap '' XFSZ; exec '$ER' '$tmp/hm.pgm' --steps 1 --wind 1,0,-1 --size 64 -o '$tmp/hf/k'"
  check "erode under ulimit -f: exit 1, the existing k_map.pfm unchanged, no .tmp (got $rc)" \
    sh -c "[ $rc -eq 1 ] && [ \"\$(cat '$tmp/hf/k_map.pfm')\" = old ] && ! ls '$tmp/hf' | grep -q 'k.*tmp'"
else
  bad "erode could not be built (make $B/erode)"
fi

echo "TESTCOUNT tools_cli passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
