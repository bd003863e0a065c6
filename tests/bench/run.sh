#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# One entry command for the benchmarks: builds the tools and harness programs, fetches the
# corpus, runs every available simplifier and codec side by side, writes bench-out/
# (RESULTS.md, results.json, error_mean.png, error_max.png).
#
# Usage: bash tests/bench/run.sh [--quick] [--build DIR] [other bench.py options...]
#   PMZ_BUILD=DIR is the same as --build DIR (default: build).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${PMZ_BUILD:-build}
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
if [ ! -f "$build/build.ninja" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
targets=(pmz-compare pmz-simplify pmz-encode pmz-decode bench-subdivide bench-openmesh-decimate)
if ninja -C "$build" -t targets all 2>/dev/null | grep -q '^bench-meshopt-simplify:'; then
  targets+=(bench-meshopt-simplify)
fi
ninja -C "$build" -j "$(nproc)" "${targets[@]}"
bash scripts/fetch_corpus.sh "$build"
py=python3
# Debian's python3-matplotlib lives in the system interpreter (a pyenv python3 may lack it).
[ -x /usr/bin/python3 ] && py=/usr/bin/python3
"$py" tests/bench/bench.py --build "$build" "${args[@]}"
