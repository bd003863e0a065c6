// SPDX-License-Identifier: MIT
// What the WebAssembly module imports from its host beyond emscripten's own (em++ --js-library
// in scripts/web.sh, which only checks the names: web/src/pmz_wasm.js provides them).
mergeInto(LibraryManager.library, {
  pmz_host_tan: (x) => Math.tan(x),
});
