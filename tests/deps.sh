#!/usr/bin/env bash
# deps.sh - install what the tests (or benches) need, when it is missing. Idempotent: when everything is
# present it only asks dpkg and returns. As root it installs with apt-get; otherwise it prints exactly what
# to install and returns 0, and tests/run.sh skips (and names) every check that needs what is missing.
#
#   tests/deps.sh test     packages for `make test` and `make sanitize`
#   tests/deps.sh bench    the above plus the benchmark peers
#   tests/deps.sh --list test|bench   print the package names only
set -u
test_pkgs="locales python3 pngcheck g++ clang libclang-rt-dev libopenmesh-dev libembree-dev libmeshoptimizer-dev glmark2-data assimp-testmodels assimp-utils libpng-dev libcgal-demo"
bench_pkgs="$test_pkgs libosmesa6-dev libsuitesparse-dev libopenblas0-serial libeigen3-dev libcgal-dev libtinyobjloader-dev libassimp-dev"

list=0
[ "${1:-}" = --list ] && { list=1; shift; }
case "${1:-test}" in
  test) pkgs=$test_pkgs ;;
  bench) pkgs=$bench_pkgs ;;
  *) echo "usage: tests/deps.sh [--list] test|bench" >&2; exit 2 ;;
esac
[ $list = 1 ] && { echo "$pkgs"; exit 0; }

if ! command -v dpkg-query >/dev/null 2>&1; then
  echo "deps: not a Debian system; make sure these (Debian names) are present: $pkgs" >&2
  exit 0
fi
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing="$missing $p"
done
# meshio's writers are tested under a locale whose decimal separator is a comma
need_locale=0
locale -a 2>/dev/null | grep -qi '^de_DE\.utf-\?8$' || need_locale=1
make_locale() {
  [ $need_locale = 1 ] && [ "$(id -u)" = 0 ] && command -v localedef >/dev/null 2>&1 &&
    { localedef -i de_DE -f UTF-8 de_DE.UTF-8 2>/dev/null || echo "deps: could not generate de_DE.UTF-8" >&2; }
  return 0
}
if [ -z "$missing" ]; then
  make_locale
  [ $need_locale = 1 ] && [ "$(id -u)" != 0 ] && echo "deps: no de_DE.UTF-8 locale (as root: localedef -i de_DE -f UTF-8 de_DE.UTF-8); the comma-locale checks are reported as SKIP" >&2
  exit 0
fi

if [ "$(id -u)" != 0 ]; then
  echo "deps: missing:$missing" >&2
  echo "deps: install them with: sudo apt-get install -y$missing" >&2
  echo "deps: continuing; the checks that need them are reported as SKIP" >&2
  exit 0
fi
echo "deps: installing:$missing" >&2
export DEBIAN_FRONTEND=noninteractive
if ! apt-get install -y -q --no-install-recommends $missing >/dev/null 2>&1; then
  apt-get update -q >/dev/null 2>&1
  if ! apt-get install -y -q --no-install-recommends $missing >&2; then
    echo "deps: apt-get install failed; the checks that need:$missing are reported as SKIP" >&2
  fi
fi
make_locale
exit 0
