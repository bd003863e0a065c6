#!/usr/bin/env bash
# Fails when a tracked C/C++ source differs from .clang-format's output (clang-format 14,
# Debian 12's). Fix with: git ls-files '*.cpp' '*.hpp' '*.h' '*.c' | xargs clang-format -i
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v clang-format >/dev/null; then
  echo "check_format: clang-format not installed (apt-get install clang-format)" >&2
  exit 1
fi
bad=()
while IFS= read -r f; do
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done < <(git ls-files '*.cpp' '*.hpp' '*.h' '*.c')
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: ${#bad[@]} file(s) not formatted: ${bad[*]}" >&2
  echo "check_format: run: git ls-files '*.cpp' '*.hpp' '*.h' '*.c' | xargs clang-format -i" >&2
  exit 1
fi
echo "check_format: all sources formatted"
