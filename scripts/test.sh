#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The whole test suite, as CI runs it:
#   1. Release build + ctest (with the real-mesh corpus from libcgal-demo; where apt-get exists a
#      failed fetch fails the run, see below),
#   2. the same suite under AddressSanitizer + UndefinedBehaviorSanitizer,
#   3. each libFuzzer target for a short fixed time (PMZ_FUZZ_SECONDS, default 30),
#   web: the WebAssembly decoder, npm package and viewer (scripts/web.sh test: node + Chromium).
# PMZ_TEST_STAGES selects stages (default "release web fuzz asan": ctest's summary comes last).
set -euo pipefail
cd "$(dirname "$0")/.."
stages=${PMZ_TEST_STAGES:-release web fuzz asan}
jobs=$(nproc)

bash scripts/setup.sh build
bash scripts/check_format.sh
bash scripts/check_words.sh
# The corpus is fetched with apt-get: where apt-get exists a failed fetch fails the run (the
# real-mesh tests would otherwise skip silently), unless PMZ_CORPUS_OPTIONAL=1 says to go on.
if bash scripts/fetch_corpus.sh build; then
  export PMZ_REQUIRE_CORPUS=1  # the corpus tests fail, not skip, on a missing mesh
elif command -v apt-get >/dev/null && [ "${PMZ_CORPUS_OPTIONAL:-0}" != 1 ]; then
  echo "test: corpus fetch failed (PMZ_CORPUS_OPTIONAL=1 runs without it; real-mesh tests skip)" >&2
  exit 1
else
  echo "test: corpus unavailable; real-mesh tests will skip" >&2
fi
export PMZ_CORPUS=$PWD/corpus
if ! bash scripts/fetch_assimp_models.sh; then
  echo "test: assimp-testmodels unavailable; its tests will skip" >&2
fi
if ! bash scripts/install_gltf_validator.sh build; then
  echo "test: gltf-validator unavailable; the .glb validation test will skip (fails under CI)" >&2
fi
export PMZ_GLTF_VALIDATOR=$PWD/build/gltf-validator

for stage in $stages; do
  case $stage in
    release)
      echo "== stage: release"
      (cd build && ctest --output-on-failure -j "$jobs" --timeout 900)
      ;;
    web)
      echo "== stage: web"
      bash scripts/web.sh test
      ;;
    asan)
      echo "== stage: address,undefined sanitizers"
      cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DPMZ_SANITIZE=address,undefined -DPMZ_BUILD_VIEWER=OFF >/dev/null
      cmake --build build-asan -j "$jobs"
      (cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
        ctest --output-on-failure -j "$jobs" --timeout 1800)
      ;;
    fuzz)
      if [ -x tests/fuzz/run.sh ] || [ -f tests/fuzz/run.sh ]; then
        echo "== stage: fuzz (${PMZ_FUZZ_SECONDS:-30} s per target)"
        bash tests/fuzz/run.sh "${PMZ_FUZZ_SECONDS:-30}"
      fi
      ;;
    *) echo "test: unknown stage $stage" >&2; exit 2 ;;
  esac
done
