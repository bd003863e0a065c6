#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# scripts/check_words.sh on planted lines in a temporary file: each narrating line is flagged
# (exit 1, "file:line:" named), and lines that only look alike (s32(x), helper_function, -s14,
# a section reference) pass. The words are assembled from pieces so that this file itself
# passes the check.
set -euo pipefail
check="$(cd "$(dirname "$0")/../.." && pwd)/scripts/check_words.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

flagged=(
  "// Fixed in ses""sion 27 after a crash."
  "# the sizes of s""28 and later"
  "/* the budget of is""sue 17 */"
  "see is""sue #5"
  "(ta""sk 3)"
  "as the le""ad asked"
  "a hel""per ran the corpus"
  "We tr""ied three weights"
  "we meas""ured 2.3x"
  "per the bri""ef"
  "(the run of 27's tr""ace)"
)
passing=(
  "x = s32(pred[a] + r[a])"
  "helper_function(); // the code both tools share"
  "cc -s14 -o out"
  "spec/format.md section 12's statuses"
  "two issues remain open in the tracker of a dependency"
)

for line in "${flagged[@]}"; do
  printf 'clean first line\n%s\n' "$line" >"$tmp/planted.cpp"
  if out=$(bash "$check" "$tmp/planted.cpp" 2>&1); then
    echo "FAIL: not flagged: $line" >&2
    fail=1
  elif ! grep -qF "$tmp/planted.cpp:2: $line" <<<"$out"; then
    echo "FAIL: flagged without file:line: $line: $out" >&2
    fail=1
  fi
done

printf '%s\n' "${passing[@]}" >"$tmp/clean.cpp"
if ! out=$(bash "$check" "$tmp/clean.cpp" 2>&1); then
  echo "FAIL: a clean file was flagged: $out" >&2
  fail=1
fi

# Several files: only the narrating line of the second one, and the count.
printf '%s\n' "${passing[@]}" "${flagged[0]}" >"$tmp/b.py"
if out=$(bash "$check" "$tmp/clean.cpp" "$tmp/b.py" 2>&1); then
  echo "FAIL: two files, one hit: exit 0" >&2
  fail=1
elif [ "$(grep -c "^$tmp/" <<<"$out")" != 1 ] || ! grep -q "^$tmp/b.py:6: " <<<"$out"; then
  echo "FAIL: two files, one hit: $out" >&2
  fail=1
fi

# A missing file is an error of its own (exit 2), not a pass.
set +e
bash "$check" "$tmp/missing.cpp" >/dev/null 2>&1
rc=$?
set -e
if [ $rc != 2 ]; then
  echo "FAIL: a missing file gave exit $rc, not 2" >&2
  fail=1
fi

[ $fail = 0 ] && echo "check_words_test: ${#flagged[@]} planted lines flagged, ${#passing[@]} look-alikes pass"
exit $fail
