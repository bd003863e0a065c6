#!/usr/bin/env bash
# pmz in the browser: builds the WebAssembly decoder (Debian's emscripten), the npm package
# pmz-decoder (ES module + TypeScript declarations + three.js loader) and the web viewer.
# Installs what is missing first (apt: emscripten, chromium; npm: web/'s devDependencies).
#
#   bash scripts/web.sh          build: web/dist/pmz-decoder-VERSION.tgz (npm pack) and
#                                web/dist/viewer/index.html (static files, ?src=URL)
#   bash scripts/web.sh test     build, then the node API tests and the headless Chromium tests
#
# Build knobs (defaults; docs/design.md section 9 says why): PMZ_WASM_OPT, the
# refinement loop's files (-O3); PMZ_WASM_COLD_OPT, the other files (-Os); PMZ_WASM_LINK_OPT, the
# LTO link (-Os); PMZ_WASM_POST_OPT, binaryen's wasm-opt after the link ("-Oz --converge"; empty:
# none); PMZ_WASM_FEATURES, the wasm features (bulk memory, non-trapping float-to-int,
# sign extension: every browser since 2021 and node 16+); PMZ_WASM_MALLOC (emmalloc).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
mode=${1:-build}

packages=(emscripten chromium)
command -v npm >/dev/null || packages+=(nodejs npm)
bash scripts/install_packages.sh web "${packages[@]}"
# Debian's emscripten takes acorn and friends from /usr/share/nodejs (node-acorn), which a node
# that is not Debian's own does not search.
export NODE_PATH=/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}

if [ ! -d web/node_modules/three ] || [ ! -d web/node_modules/puppeteer-core ]; then
  echo "web: npm install (web/)" >&2
  (cd web && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
fi

# The decoder library's sources: standard C++ only, linked with LTO (the writer-side code in
# format/ is dropped). Size budget (issue 16: .wasm + pmz_wasm.js at most 120,000 bytes, 50 KB
# gzip): the refinement loop's files are compiled -O3 ($opt), the rest -Os: the chunk set-up
# (coding.cpp: byte reader, CRC, range decoder set-up), the base mesh, attributes, the C API
# (the -O3 files' own once-per-chunk functions are minsize in wasm: PMZ_SMALL_IN_WASM). Every
# other decoder source (a new file) is -Os too.
hot=(decoder/src/decoder.cpp format/src/split_chunk.cpp format/src/vertex_choice.cpp
  format/src/progressive_mesh.cpp format/src/geometry.cpp format/src/fan_wedge.cpp
  format/src/speed_level.cpp)
cold=()
for f in decoder/src/*.cpp format/src/*.cpp; do
  [[ " ${hot[*]} " == *" $f "* ]] || cold+=("$f")
done
exports=$(sed -n 's/^[a-zA-Z][^(]* \**\(pmz_[a-z_]*\)(.*/"_\1"/p' decoder/include/pmz/pmz.h | paste -sd,)
opt=${PMZ_WASM_OPT:--O3}
cold_opt=${PMZ_WASM_COLD_OPT:--Os}
link_opt=${PMZ_WASM_LINK_OPT:--Os}
post_opt=${PMZ_WASM_POST_OPT--Oz --converge}
out=web/build
pkg=web/dist/pkg
obj=$out/obj
rm -rf "$obj" && mkdir -p "$out" "$pkg" "$obj/hot" "$obj/cold"
features=(${PMZ_WASM_FEATURES--mbulk-memory -mnontrapping-fptoint -msign-ext})
cxxflags=(-std=c++20 -flto -fno-exceptions "${features[@]}" -Wall -Wextra
  -I"$root/decoder/include" -I"$root/format/include")
# Each set in one em++ call (objects land in the current directory), the two sets in parallel.
(cd "$obj/hot" && em++ "${cxxflags[@]}" $opt -c "${hot[@]/#/$root/}") &
hot_job=$!
(cd "$obj/cold" && em++ "${cxxflags[@]}" $cold_opt -c "${cold[@]/#/$root/}")
wait "$hot_job"
# A standalone module (no emscripten JS runtime: web/src/pmz_wasm.js instantiates it, 2 KB
# instead of emscripten's 14 KB of glue). -sFILESYSTEM=0: no file I/O. -fno-exceptions (above): a
# failed allocation aborts, which the JS wrapper reports as out_of_memory, the only exception the
# decoder can meet; the decoder's handlers are PMZ_TRY / PMZ_CATCH_BAD_ALLOC (wasm_hints.hpp), and
# without the throw/catch runtime and its RTTI the module is 944 B smaller. emmalloc: 7.7 KB
# smaller than dlmalloc, as fast here (the decoder makes few, large allocations). Linking -Os and
# wasm-opt -Oz after it: -3.4 KB, no slower (the hot files' -O3 inlining and unrolling happen
# before the link).
em++ $link_opt -flto "${features[@]}" "$obj"/hot/*.o "$obj"/cold/*.o \
  -o "$out/pmz_wasm.wasm" --no-entry -sSTANDALONE_WASM=1 -sFILESYSTEM=0 -sALLOW_MEMORY_GROWTH=1 \
  -sWASM_BIGINT=1 -sMALLOC=${PMZ_WASM_MALLOC:-emmalloc} -sEXPORTED_FUNCTIONS="[$exports,\"_malloc\",\"_free\"]"
# (wasm-opt takes the features from the module's target_features section.)
[ -z "$post_opt" ] || wasm-opt $post_opt "$out/pmz_wasm.wasm" -o "$out/pmz_wasm.wasm"

rm -rf "$pkg" && mkdir -p "$pkg"
cp web/pkg/package.json web/pkg/README.md "$pkg/"
cp web/src/*.js web/src/*.d.ts "$out/pmz_wasm.wasm" "$pkg/"
rm -f web/dist/*.tgz
(cd "$pkg" && npm pack --silent --pack-destination "$root/web/dist" >/dev/null)

# The viewer: static files; three and the package resolved by an import map.
viewer=web/dist/viewer
rm -rf "$viewer" && mkdir -p "$viewer/vendor"
cp web/viewer/* "$viewer/"
cp -r "$pkg" "$viewer/pmz"
# Module workers have no import map (the viewer draws in one): its copy of the loader imports
# three by path, the same module the page's import map gives.
sed -i "s#from 'three';#from '../vendor/three.module.js';#" "$viewer/pmz/three.js"
cp web/node_modules/three/build/three.module.js "$viewer/vendor/"
cp web/node_modules/three/examples/jsm/controls/OrbitControls.js "$viewer/vendor/"

wasm_bytes=$(stat -c %s "$out/pmz_wasm.wasm")
glue_bytes=$(stat -c %s web/src/pmz_wasm.js)
gz_bytes=$(cat "$out/pmz_wasm.wasm" web/src/pmz_wasm.js | gzip -9 | wc -c)
echo "web: $(ls web/dist/*.tgz), $viewer/index.html; wasm $wasm_bytes + glue $glue_bytes bytes" \
  "($gz_bytes gzip -9)" >&2

if [ "$mode" = test ]; then
  bin=${PMZ_BIN:-$root/build/bin}
  # pmz-encode and pmz-dump-arrays: the attribute tests' streams and native reference arrays.
  tools=(pmz-decode pmz-demo pmz-encode pmz-dump-arrays)
  for t in "${tools[@]}"; do
    if [ ! -x "$bin/$t" ]; then
      cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
      cmake --build build -j "$(nproc)" --target "${tools[@]}"
      break
    fi
  done
  sample=web/build/demo/sample.pmz
  if [ ! -f "$sample" ] || [ "$bin/pmz-demo" -nt "$sample" ]; then
    "$bin/pmz-demo" web/build/demo >/dev/null
  fi
  PMZ_BIN=$bin PMZ_WEB_SAMPLE=$PWD/$sample node --test web/test/*.test.mjs
elif [ "$mode" != build ]; then
  echo "web: unknown mode $mode (build or test)" >&2
  exit 2
fi
