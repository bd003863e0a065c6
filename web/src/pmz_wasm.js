// Instantiates pmz_wasm.wasm: the decoder built by emscripten as a standalone module
// (scripts/web.sh: -sSTANDALONE_WASM, no emscripten JS runtime). It owns its memory and
// imports two functions; this file is the whole JS side of it (emscripten's generated glue was
// 14 KB of the 120 KB size budget).
//
// Returns { HEAPU8, _name for each exported function } like an emscripten module, so the
// wrapper in index.js calls `_pmz_decoder_feed`, `_malloc`, ... directly.
export default async function createModule(options = {}) {
  const imports = {
    // A failed allocation or a throw (exceptions are not compiled in) ends in abort(): the
    // instance is unusable from then on and the caller's try/catch reports it.
    wasi_snapshot_preview1: {
      proc_exit(code) { throw new Error(`pmz: the WebAssembly instance aborted (exit ${code})`); },
    },
    // memory.grow detaches the old buffer; HEAPU8 below notices by itself.
    env: { emscripten_notify_memory_growth() {} },
  };
  let source;
  if (options.wasmBinary) {
    source = await WebAssembly.instantiate(options.wasmBinary, imports);
  } else {
    const url = new URL('./pmz_wasm.wasm', import.meta.url);
    const response = fetch(url, { credentials: 'same-origin' });
    try {
      source = await WebAssembly.instantiateStreaming(response, imports);
    } catch (e) {  // e.g. served without Content-Type application/wasm
      const r = await response;
      if (!r.ok) throw new Error(`pmz: ${url}: HTTP ${r.status}`);
      source = await WebAssembly.instantiate(await r.arrayBuffer(), imports);
    }
  }
  const exports = source.instance.exports;
  const memory = exports.memory;
  let heap = new Uint8Array(memory.buffer);
  const module = {
    get HEAPU8() {
      if (heap.buffer !== memory.buffer) heap = new Uint8Array(memory.buffer);
      return heap;
    },
  };
  for (const [name, value] of Object.entries(exports))
    if (typeof value === 'function') module['_' + name] = value;
  exports._initialize();  // static constructors
  return module;
}
