#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (clang-14, ASan + UBSan) and runs each for SECONDS (default 60).
#   usage: tests/fuzz/run.sh [SECONDS]
#   env:   PMZ_FUZZ_BUILD  build directory (default build-fuzz, relative to the repository)
#          PMZ_ENCODE      pmz-encode for richer seeds (default build/bin/pmz-encode if present)
#          PMZ_FUZZ_TARGETS  subset, e.g. "fuzz_decoder"
#          PMZ_FUZZ_TIMEOUT  seconds one input may take before it counts as a hang (default 10;
#                            raise it for a niced run on a loaded machine, where a 20 ms input
#                            can wait that long for the CPU)
# The corpus grows in $PMZ_FUZZ_BUILD/fuzz/corpus/<target> across runs; crashes land in
# $PMZ_FUZZ_BUILD/fuzz/artifacts/ and make the script fail. Each crash deserves a regression
# test in tests/decoder/test_hostile.cpp (the hostile-input suite: the input, as bytes or as the
# construction that makes it, and what the decoder must answer); a crash of fuzz_region, in
# tests/tools/test_cli.py (a real region damaged in the same way, refused by pmz-encode --task).
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
build=${PMZ_FUZZ_BUILD:-build-fuzz}
targets=${PMZ_FUZZ_TARGETS:-fuzz_decoder fuzz_container fuzz_coding fuzz_view fuzz_mesh_obj fuzz_mesh_off
  fuzz_mesh_ply fuzz_mesh_stl fuzz_mesh_gltf fuzz_mesh_repair fuzz_region}

if ! command -v clang++-14 >/dev/null; then
  echo "fuzz: clang++-14 missing (apt-get install clang-14 libclang-rt-14-dev)" >&2
  exit 2
fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_C_COMPILER=clang-14 \
  -DPMZ_BUILD_FUZZERS=ON -DPMZ_BUILD_VIEWER=OFF -DPMZ_BUILD_ENCODER=ON >/dev/null
# shellcheck disable=SC2086
cmake --build "$build" -j "$(nproc)" --target $targets

encoder=${PMZ_ENCODE:-}
if [ -z "$encoder" ] && [ -x build/bin/pmz-encode ]; then encoder=build/bin/pmz-encode; fi
work=$build/fuzz
python3 tests/fuzz/make_seeds.py "$work/seeds" "$encoder"
python3 tests/fuzz/make_mesh_seeds.py "$work/seeds"
mkdir -p "$work/artifacts"

failed=0
for t in $targets; do
  part=${t#fuzz_}
  max_len=16384
  [ "$t" = fuzz_region ] && max_len=131072  # (a small mesh's regions are 5-100 KB)
  mkdir -p "$work/corpus/$t"
  log=$work/$t.log
  echo "== $t for ${seconds}s"
  # Limits: the targets decode with DecoderLimits of 1M vertices / 4 MB chunks, so any single
  # allocation above 256 MB is a missed cap; 10 s for one input is a hang.
  if "$build/bin/$t" -max_total_time="$seconds" -timeout="${PMZ_FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 \
      -malloc_limit_mb=256 -max_len="$max_len" -print_final_stats=1 \
      -artifact_prefix="$work/artifacts/$t-" "$work/corpus/$t" "$work/seeds/$part" >"$log" 2>&1; then
    status=ok
  else
    status=FAILED
    failed=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1)
  echo "$t: $status, ${runs:-?} executions, ${cov:-no coverage line}"
  if [ "$status" != ok ]; then
    grep -m1 -E 'ERROR|invariant violated|SUMMARY' "$log" >&2 || true
    ls "$work/artifacts" | grep "^$t-" >&2 || true
    echo "full log: $log" >&2
  fi
done
exit $failed
