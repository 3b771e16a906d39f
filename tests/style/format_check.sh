#!/usr/bin/env bash
# Every C and C++ source of rths is as .clang-format writes it: `clang-format --dry-run -Werror`
# over the tracked sources (or, outside a git checkout, every source under the tree but build/
# and node_modules/). Prints each offending file and line; exits 77 (skipped) without clang-format.
#   format_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
fmt=$(command -v clang-format-14 || command -v clang-format || true)
if [ -z "$fmt" ]; then
  echo "skipped: clang-format is not installed (apt-get install clang-format)"
  exit 77
fi
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.h' '*.c')
else
  mapfile -t files < <(find . \( -path ./build -o -name node_modules -o -path './build*' \) -prune \
    -o \( -name '*.cpp' -o -name '*.h' -o -name '*.c' \) -print)
fi
echo "checking ${#files[@]} files with $("$fmt" --version)"
"$fmt" --dry-run -Werror "${files[@]}"
echo "all ${#files[@]} files formatted"
