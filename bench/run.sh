#!/bin/sh
# run.sh BUILD_DIR [MESH] - run every built bench on MESH (default BUILD_DIR/sphere1m.off) and write
# bench/RESULTS.md from their RESULT lines. Progress and each bench's stderr go to the terminal.
set -u
B="$1"
MESH="${2:-$B/sphere1m.off}"
out=bench/RESULTS.md
tmp="$B/bench_results.txt"
: > "$tmp"
status=0
for prog in "$B"/bench_*; do
  [ -x "$prog" ] || continue
  echo "bench: $(basename "$prog") $MESH" >&2
  if ! "$prog" "$MESH" >>"$tmp"; then
    echo "bench: $(basename "$prog") failed" >&2
    status=1
  fi
done
{
  echo "# Benchmark results"
  echo
  echo "Written by \`make bench\` on $(date -u '+%Y-%m-%d %H:%M UTC'); machine: $(nproc) cores,"
  echo "$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | sed 's/.*: //'); input: \`$MESH\`."
  echo "Every figure is the median of 5 runs after a warm-up, both sides in one process, one thread each;"
  echo "the timed regions are described in bench/README.md. Ratios are ours / peer (below 1 means faster)."
  echo
  echo '| bench | figures |'
  echo '|---|---|'
  grep '^RESULT ' "$tmp" | while read -r _ name rest; do echo "| $name | $rest |"; done
} > "$out"
grep '^RESULT ' "$tmp"
echo "bench: wrote $out" >&2
exit $status
