#!/bin/bash
# Formats every C++ file git tracks with the repository's .clang-format (clang-format 14, Debian's
# clang-format package). --check changes nothing: it lists the files that differ and exits 1 if any.
set -eu
cd "$(dirname "$0")/.."
files=$(git ls-files '*.cpp' '*.h')
if [ "${1:-}" = "--check" ]; then
  differ=0
  for f in $files; do
    if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then echo "$f"; differ=1; fi
  done
  exit $differ
fi
echo "$files" | xargs clang-format -i
