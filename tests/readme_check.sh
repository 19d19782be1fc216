#!/bin/sh
# readme_check.sh BUILD_DIR - README.md stands on its own in a clone (issue 21, point 7):
#   - it starts with exactly the two commands `make demo` and `make test` (its first code block);
#   - every link target [..](PATH) and every path written in backquotes (a word with a / or ending
#     in a file extension we ship: .h .c .cpp .hpp .sh .md .mk .png .tsv .txt) names a file or
#     directory of this repository: no absolute path, no "..", no URL; build/ and out/ paths
#     (what make writes) and words with a placeholder (PREFIX_base.obj, OUT.png, FILE, NAME) are skipped;
#   - every picture ![..](PATH) exists, is a PNG (signature) and at most 60 KiB (the gallery's
#     bound, docs/thumbnail.c);
#   - every ```c block is a translation unit that compiles alone with the headers, as C99 and as
#     C++11 (when a C++ compiler is present), -Wall -Wextra -pedantic -Werror: the usage snippets
#     are the headers' real API;
#   - it names every header of the repository (the library headers and examples/*.h), and each
#     has a snippet that includes it.
B="$1"
top=$(cd "$(dirname "$0")/.." && pwd)
readme="$top/README.md"
pass=0; fail=0; skip=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
check() { what="$1"; shift; if "$@"; then ok; else bad "$what"; fi; }
LC_ALL=C; export LC_ALL
case "$B" in /*) ;; *) B="$top/$B" ;; esac
work="$B/readme_check"
rm -rf "$work"; mkdir -p "$work"

# ---- the first two commands -------------------------------------------------------------------------
first=$(awk '/^```/ { if (inblock) exit; inblock = 1; next } inblock && NF { sub(/[ \t]*#.*/, ""); print }' "$readme")
check "README's first code block is exactly 'make demo' then 'make test' (got: $(echo "$first" | tr '\n' ';'))" \
  [ "$first" = "make demo
make test" ]

# ---- links and paths (outside code blocks) ------------------------------------------------------------
awk '/^```/ { inblock = !inblock; next } !inblock' "$readme" >"$work/prose.md"
# markdown link and picture targets
grep -o -E '!?\[[^]]*\]\([^)]*\)' "$work/prose.md" | sed -E 's/^!?\[[^]]*\]\(([^) ]*).*/\1/' | sort -u >"$work/links.txt"
# backquoted words that look like paths
grep -o -E '`[^`]+`' "$work/prose.md" | tr -d '`' | tr ' ' '\n' |
  grep -E '^[A-Za-z0-9_.+/-]+$' | grep -E '/|\.(h|c|cpp|hpp|sh|md|mk|png|tsv|txt)$' |
  grep -v -E '^(build|out)/|PREFIX|OUT\.|FILE|NAME|GREY|^-' | sort -u >"$work/paths.txt"
n_links=$(wc -l <"$work/links.txt"); n_paths=$(wc -l <"$work/paths.txt")
check "README has links to check ($n_links)" [ "$n_links" -gt 0 ]
for target in $(cat "$work/links.txt" "$work/paths.txt"); do
  path=${target%%#*}
  case "$path" in
    *://*|/*|*..*) bad "README names '$target': outside the repository (a URL, an absolute path or ..)"; continue ;;
  esac
  check "README names '$target', which does not exist in the repository" [ -e "$top/$path" ]
done
echo "readme_check: $n_links link targets, $n_paths paths checked"

# ---- pictures ------------------------------------------------------------------------------------------
grep -o -E '!\[[^]]*\]\([^)]*\)' "$work/prose.md" | sed -E 's/^!\[[^]]*\]\(([^) ]*).*/\1/' | sort -u >"$work/pictures.txt"
n_pics=$(wc -l <"$work/pictures.txt")
check "README shows pictures ($n_pics)" [ "$n_pics" -gt 0 ]
for pic in $(cat "$work/pictures.txt"); do
  f="$top/$pic"
  [ -f "$f" ] || { bad "picture $pic does not exist"; continue; }
  check "picture $pic is a PNG" [ "$(od -An -tx1 -N8 "$f" | tr -d ' \n')" = 89504e470d0a1a0a ]
  size=$(wc -c <"$f")
  check "picture $pic is at most 60 KiB ($size bytes)" [ "$size" -le 61440 ]
done

# ---- every header is named ----------------------------------------------------------------------------
for h in $(cd "$top" && ls *.h examples/*.h 2>/dev/null); do
  check "README names the header $h" grep -q -F "$(basename "$h")" "$readme"
done

# ---- the snippets compile --------------------------------------------------------------------------------
awk -v dir="$work" '/^```c$/ { n++; f = sprintf("%s/snippet%02d.c", dir, n); inblock = 1; next }
                    /^```/ { inblock = 0; next } inblock { print > f }' "$readme"
n_snip=$(ls "$work"/snippet*.c 2>/dev/null | wc -l)
check "README has C snippets ($n_snip)" [ "$n_snip" -ge 6 ]
CC="${CC:-cc}"
CXX=""
for c in g++ clang++; do command -v $c >/dev/null 2>&1 && { CXX=$c; break; }; done
for s in "$work"/snippet*.c; do
  [ -f "$s" ] || continue
  name=$(basename "$s" .c)
  what="$(grep -m1 -o -E '#include "[^"]+"' "$s")"
  if $CC -std=c99 -Wall -Wextra -pedantic -Werror -I"$top" -I"$top/examples" -c "$s" -o "$work/$name.o" 2>"$work/$name.err"; then ok
  else bad "README $name ($what) does not compile as C99: $(head -c 600 "$work/$name.err")"; fi
  if [ -n "$CXX" ]; then
    if $CXX -x c++ -std=c++11 -Wall -Wextra -pedantic -Werror -I"$top" -I"$top/examples" -c "$s" -o "$work/$name.cxx.o" 2>"$work/$name.cxx.err"; then ok
    else bad "README $name ($what) does not compile as C++11: $(head -c 600 "$work/$name.cxx.err")"; fi
  else
    echo "SKIP README $name as C++: no C++ compiler"; skip=$((skip + 1))
  fi
done
echo "readme_check: $n_snip snippets compiled"
for h in $(cd "$top" && ls *.h examples/*.h 2>/dev/null); do
  check "README has a snippet that includes $(basename "$h")" sh -c "cat '$work'/snippet*.c | grep -q -F '#include \"$(basename "$h")\"'"
done

echo "TESTCOUNT readme_check passed=$pass failed=$fail skipped=$skip"
[ $fail -eq 0 ]
