#!/usr/bin/env bash
# run.sh - run every test listed in tests/tests.list against one build directory and add up the counts.
#
#   tests/run.sh BUILD_DIR [sanitize]
#
# Each test prints "TESTCOUNT name passed=N failed=N skipped=N" (tests/test.h does it); a program that
# prints none counts as one check, passed when it exits 0. A program that crashes, times out or exits
# non-zero is a failure even if its counts say otherwise. A test whose binary was not built because a
# package is missing is reported as SKIP with the package to install. The last line is
#   N passed, N failed, N skipped
set -u
top=$(cd "$(dirname "$0")/.." && pwd)
B="$1"
mode="${2:-normal}"
logs="$B/logs"; mkdir -p "$logs"
export B TOP="$top"
[ "$mode" = sanitize ] && export TEST_SANITIZE=1
HEADERS="${HEADERS:-}"; export HEADERS

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

total_p=0; total_f=0; total_s=0
while read -r name needs where cmd; do
  case "$name" in ''|'#'*) continue ;; esac
  if [ "$mode" = sanitize ] && [ "$where" = nosan ]; then continue; fi
  prog=$(eval echo "${cmd%% *}")
  if [ ! -x "$prog" ]; then
    if [ "$needs" != - ]; then
      why="not built"
      for p in ${needs//,/ }; do installed "$p" || why="needs $p (apt-get install $p)"; done
      echo "SKIP $name: $why"
      total_s=$((total_s + 1))
    else
      echo "FAIL $name: $prog was not built"
      total_f=$((total_f + 1))
    fi
    continue
  fi
  start=$(date +%s.%N)
  ( cd "$top" && eval "timeout 1200 $cmd" ) >"$logs/$name.log" 2>&1
  rc=$?
  secs=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  grep -E '^(FAIL|SKIP|  values|  note)' "$logs/$name.log" | head -n 40
  counts=$(grep -E '^TESTCOUNT ' "$logs/$name.log")
  p=0; f=0; s=0
  if [ -n "$counts" ]; then
    while read -r _ _ pp ff ss; do
      p=$((p + ${pp#passed=})); f=$((f + ${ff#failed=})); s=$((s + ${ss#skipped=}))
    done <<<"$counts"
  elif [ $rc -eq 0 ]; then p=1
  fi
  if [ $rc -ne 0 ] && [ $f -eq 0 ]; then
    f=1
    echo "FAIL $name: exited with status $rc (see $logs/$name.log):"
    tail -n 15 "$logs/$name.log" | sed 's/^/    /'
  fi
  status=ok; [ $f -ne 0 ] && status=FAIL
  printf '%-4s %-24s %6d passed %4d failed %4d skipped  %6.1f s\n' "$status" "$name" $p $f $s "$secs"
  total_p=$((total_p + p)); total_f=$((total_f + f)); total_s=$((total_s + s))
done < "$top/tests/tests.list"
echo "$total_p passed, $total_f failed, $total_s skipped"
[ $total_f -eq 0 ]
