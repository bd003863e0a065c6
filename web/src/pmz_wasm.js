// SPDX-License-Identifier: MIT
// Instantiates pmz_wasm.wasm, the decoder as a standalone module (scripts/web.sh): the whole JS
// side of it. Returns { HEAPU8, _name per export } like an emscripten module (index.js calls
// _pmz_decoder_feed, _malloc, ...). Kept short: its bytes count in the size budget.
export default async function createModule(options = {}) {
  const imports = {
    // abort() (a failed allocation or a throw): the caller's try/catch reports it.
    wasi_snapshot_preview1: {
      proc_exit(code) { throw new Error(`pmz: the WebAssembly instance aborted (exit ${code})`); },
    },
    // (HEAPU8 notices memory growth by itself; pmz_host_tan: web/wasm_imports.js)
    env: { emscripten_notify_memory_growth() {}, pmz_host_tan: Math.tan },
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
    get HEAPU8() {  // memory.grow detaches the old buffer
      if (heap.buffer !== memory.buffer) heap = new Uint8Array(memory.buffer);
      return heap;
    },
  };
  for (const [name, value] of Object.entries(exports))
    if (typeof value === 'function') module['_' + name] = value;
  exports._initialize();  // static constructors
  return module;
}
