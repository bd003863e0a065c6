#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Fails when a tracked C/C++ source differs from .clang-format's output (clang-format 14,
# Debian 12's), or when a source file of the project's own (C/C++, JS/TS, Python, shell, CMake)
# does not start with its licence's SPDX line: "// SPDX-License-Identifier: MIT" or
# "# SPDX-License-Identifier: MIT", after the shebang of a script.
# Fix the formatting with: git ls-files '*.cpp' '*.hpp' '*.h' '*.c' | xargs clang-format -i
# usage: scripts/check_format.sh [--list-sources]   (--list-sources: the files needing the line)
set -euo pipefail
cd "$(dirname "$0")/.."

# The files that carry the SPDX line; none is generated (test vectors and data are not sources).
sources() {
  git ls-files '*.c' '*.h' '*.cpp' '*.hpp' '*.js' '*.mjs' '*.cjs' '*.ts' '*.py' '*.sh' \
    '*.cmake' '*.cmake.in' '*CMakeLists.txt' .ci/run 'scripts/git-hooks/*'
}
if [ "${1:-}" = --list-sources ]; then
  sources
  exit 0
fi

unlicensed=()
while IFS= read -r f; do
  [ -f "$f" ] || continue  # deleted in the work tree, not yet in the index
  first=$(head -n 2 "$f")
  case $first in
    '#!'*) first=$(sed -n 2p <<<"$first") ;;
    *) first=$(head -n 1 <<<"$first") ;;
  esac
  case $first in
    '// SPDX-License-Identifier: MIT' | '# SPDX-License-Identifier: MIT') ;;
    *) unlicensed+=("$f") ;;
  esac
done < <(sources)
if [ ${#unlicensed[@]} -gt 0 ]; then
  for f in "${unlicensed[@]}"; do echo "$f:1: no SPDX-License-Identifier: MIT line first" >&2; done
  echo "check_format: ${#unlicensed[@]} source(s) without the SPDX line (// or #" \
    "SPDX-License-Identifier: MIT as the first line, after a shebang)" >&2
  exit 1
fi

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
echo "check_format: all sources formatted and licensed"
