// SPDX-License-Identifier: MIT
// What the WebAssembly module imports from its host beyond emscripten's own (em++ --js-library
// in scripts/web.sh): the threaded module's glue takes them from here; for the standalone
// module it only checks the names (web/src/pmz_wasm.js provides them). Function expressions:
// emscripten 3.1.6 emits no definition for an arrow function.
mergeInto(LibraryManager.library, {
  pmz_host_tan: function (x) { return Math.tan(x); },
});
