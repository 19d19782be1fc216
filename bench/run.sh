#!/bin/sh
# run.sh BUILD_DIR [MESH...] - run every built bench on each MESH (default: BUILD_DIR/sphere1m.off and,
# when glmark2-data is installed, the Stanford bunny) and write bench/RESULTS.md from their RESULT
# lines. Progress and each bench's stderr go to the terminal.
set -u
B="$1"; shift
if [ $# -eq 0 ]; then
  set -- "$B/sphere1m.off"
  bunny=/usr/share/glmark2/models/bunny.obj
  if [ -f "$bunny" ]; then set -- "$bunny" "$@"; else echo "bench: $bunny missing (apt-get install glmark2-data)" >&2; fi
fi
out=bench/RESULTS.md
tmp="$B/bench_results.txt"
: > "$tmp"
status=0
for mesh in "$@"; do
  for prog in "$B"/bench_*; do
    [ -x "$prog" ] || continue
    case "$(basename "$prog")" in bench_texel|bench_relief|bench_deform|bench_erosion) continue ;; esac # run once below
    echo "bench: $(basename "$prog") $mesh" >&2
    if ! "$prog" "$mesh" | sed "s|^RESULT |RESULT $(basename "$mesh") |" >>"$tmp"; then
      echo "bench: $(basename "$prog") failed on $mesh" >&2
      status=1
    fi
  done
done
# runs a bench with its own arguments once: once LABEL PROG ARGS...
once() {
  label="$1"; prog="$B/$2"; shift 2
  [ -x "$prog" ] || return 0
  echo "bench: $(basename "$prog") $*" >&2
  if ! "$prog" "$@" | sed "s|^RESULT |RESULT $label |" >>"$tmp"; then
    echo "bench: $(basename "$prog") $* failed" >&2
    status=1
  fi
}
# the benches that take no mesh (their own fixed inputs), and the cases beyond one run per mesh
once texel bench_texel
once asteroid bench_relief
once erosion bench_erosion                                                         # height field + the bunny's map, 1024^2 and 4096^2
bunny=/usr/share/glmark2/models/bunny.obj
if [ -f "$bunny" ]; then
  once bunny_x1 bench_deform "$bunny" --refine 1                                  # deform.h, 139k vertices
  once bunny_x1_free1 bench_deform "$bunny" --refine 1 --free 1 --methods laplacian,lri,cgal_arap
  once bunny_x2 bench_dispmesh "$bunny" --refine 2 --base-only                    # 1,114,656 triangles
fi
{
  echo "# Benchmark results"
  echo
  echo "Written by \`make bench\` on $(date -u '+%Y-%m-%d %H:%M UTC'); machine: $(nproc) cores,"
  echo "$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | sed 's/.*: //')."
  echo "A time with \`_min\` / \`_max\` beside it is the median of 11 runs after a warm-up, the sides of a comparison"
  echo "interleaved run by run (A B A B ...) in one process; a time without them is the median of 5 runs after a warm-up."
  echo "One thread per side (bench_chol checks CHOLMOD's), the process's CPU time, every bench built with -DNDEBUG"
  echo "(bench/README.md says why);"
  echo "the timed regions are described in bench/README.md. Ratios are ours / peer: for times (\`_ms\`)"
  echo "below 1 means we are faster, for throughputs (\`_mrays\`) above 1 means we are faster."
  echo
  echo '| mesh | figure | values |'
  echo '|---|---|---|'
  grep '^RESULT ' "$tmp" | while read -r _ mesh name rest; do echo "| $mesh | $name | $rest |"; done
} > "$out"
grep '^RESULT ' "$tmp"
echo "bench: wrote $out" >&2
exit $status
