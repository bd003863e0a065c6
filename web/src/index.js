// SPDX-License-Identifier: MIT
// pmz-decoder: the pmz streaming decoder compiled to WebAssembly, wrapping its C API
// (decoder/include/pmz/pmz.h). Push model: feed() slices of a .pmz stream in any size, then
// refine() / setFaceTarget() move the mesh between the base mesh and what has arrived.
import createModule from './pmz_wasm.js';

// Status codes of pmz.h (PMZ_OK ... PMZ_ERR_MEMORY), as the names the API returns.
export const STATUS_NAMES = Object.freeze([
  'ok',
  'bad_magic',
  'bad_version',
  'bad_checksum',
  'corrupt',
  'limit_exceeded',
  'truncated',
  'out_of_memory',
]);
const ALL = 0xffffffffffffffffn;
const FEED_SLICE = 1 << 20;  // input copied into the heap at most this much at a time
const REFINE_BATCH = 16384n;  // splits per call into the instance (see refine())
const VIEW_BYTES = 88;  // sizeof(pmz_view) in wasm32

let modulePromise = null;
const threadedModules = new Map();  // workers -> the threaded module's promise

const inNode = typeof process === 'object' && !!(process.versions && process.versions.node) &&
  typeof window === 'undefined';

// The cores: navigator.hardwareConcurrency in browsers and workers, os.availableParallelism()
// (os.cpus().length before node 18.14) in node.
async function defaultWorkers() {
  if (inNode) {
    const os = await import('node:os');
    return Math.max(1, typeof os.availableParallelism === 'function' ? os.availableParallelism()
                                                                   : os.cpus().length);
  }
  return Math.max(1, (typeof navigator === 'object' && navigator.hardwareConcurrency) || 1);
}

// Whether the threaded module can run here: shared WebAssembly memory and workers, which
// browsers give only to cross-origin-isolated pages (COOP and COEP headers; web/README.md).
function threadsAvailable() {
  if (typeof SharedArrayBuffer !== 'function' || typeof Atomics !== 'object') return false;
  if (inNode) return true;
  return globalThis.crossOriginIsolated === true && typeof Worker === 'function';
}

// One WebAssembly instance serves every decoder. In node the .wasm beside this file is read
// with fs (node's fetch cannot read file: URLs); in browsers and workers it is fetched
// relative to this module.
async function instantiate(options) {
  const moduleOptions = {};
  if (options.wasmBinary) {
    moduleOptions.wasmBinary = options.wasmBinary;
  } else if (inNode) {
    const { readFile } = await import('node:fs/promises');
    moduleOptions.wasmBinary = await readFile(new URL('./pmz_wasm.wasm', import.meta.url));
  }
  return createModule(moduleOptions);
}

function loadModule(options) {
  if (options.wasmBinary) return instantiate(options);
  if (!modulePromise) {
    modulePromise = instantiate(options);
    modulePromise.catch(() => { modulePromise = null; });
  }
  return modulePromise;
}

// The threaded module (pmz_wasm_mt.js: emscripten's runtime, scripts/web.sh) with workers - 1
// web workers (node: worker_threads) beside the calling thread, made and loaded before it
// resolves. Seen by the decoder as the single-threaded module is (HEAPU8, _name per export).
async function instantiateThreaded(workers, options) {
  const { default: create } = await import('./pmz_wasm_mt.js');
  const moduleOptions = { pmzPool: workers - 1 };
  if (inNode) {
    const { readFile } = await import('node:fs/promises');
    moduleOptions.wasmBinary = await readFile(new URL('./pmz_wasm_mt.wasm', import.meta.url));
    // (the worker script is CommonJS in node: its .cjs copy; browsers take the .js beside)
    moduleOptions.locateFile = (file, dir) => dir + file.replace(/\.worker\.js$/, '.worker.cjs');
  }
  const em = await create(moduleOptions);
  const pool = em.PThread.unusedWorkers;
  // node: the idle workers do not keep the process alive.
  if (inNode) for (const w of pool) if (typeof w.unref === 'function') w.unref();
  const memory = em.wasmMemory;
  let heap = new Uint8Array(memory.buffer);
  const module = {
    workers,
    threadStarts: 0,  // threads the decoder started (pmz_decoder_refine's parallel nodes)
    // A thread that grows the memory leaves the other threads' views at the old size (a
    // SharedArrayBuffer is not detached): a view of the current size each time.
    get HEAPU8() {
      if (heap.byteLength !== memory.buffer.byteLength) heap = new Uint8Array(memory.buffer);
      return heap;
    },
  };
  const take = em.PThread.getNewWorker;
  em.PThread.getNewWorker = function getNewWorker() {
    const w = take.call(this);
    if (w) ++module.threadStarts;
    return w;
  };
  for (const [name, value] of Object.entries(em))
    if (name.startsWith('_pmz_') || name === '_malloc' || name === '_free') module[name] = value;
  return module;
}

// The module for `workers` threads: the threaded one when it can run here and more than one
// is asked for, else (or when it fails to load: e.g. its files were not deployed) the
// single-threaded one, and one worker.
function loadModuleFor(workers, options) {
  if (workers < 2 || !threadsAvailable() || options.wasmBinary) return loadModule(options);
  let p = threadedModules.get(workers);
  if (!p) {
    p = instantiateThreaded(workers, options).catch(() => loadModule(options));
    threadedModules.set(workers, p);
    p.catch(() => threadedModules.delete(workers));
  }
  return p;
}

function toU64(n) {
  if (n === undefined || n === Infinity) return ALL;
  if (typeof n === 'bigint') return n < 0n ? 0n : n & ALL;
  if (!(n > 0)) return 0n;  // also NaN
  return BigInt(Math.min(Math.floor(n), Number.MAX_SAFE_INTEGER));
}

function cString(m, ptr) {
  const heap = m.HEAPU8;
  let end = ptr;
  while (heap[end] !== 0) ++end;
  // (a copy: TextDecoder takes no view of shared memory, the threaded module's)
  return new TextDecoder().decode(heap.slice(ptr, end));
}

export class Decoder {
  constructor(module, options = {}) {
    this._m = module;
    this._dead = null;  // the error line once the WebAssembly instance aborted
    this._ptr = module._pmz_decoder_create(toU64(options.maxVertices ?? 0),
                                           toU64(options.maxFaces ?? 0));
    // Scratch for pmz_stream_info (104 bytes), pmz_changes (24), pmz_material (28), pmz_view
    // (88) with lookAt()'s eye and target (24), and nodeRange()'s two uint64.
    this._scratch = module._malloc(128);
    this._input = 0;
    this._inputSize = 0;
    if (!this._ptr || !this._scratch) throw new Error('pmz: out of memory creating a decoder');
    this._workers = module.workers || 1;
    module._pmz_decoder_set_threads(this._ptr, this._workers);
  }

  // The threads decoding: createDecoder()'s workers where the threaded module runs, else 1.
  get workers() { return this._workers; }

  // Runs a call into the instance; an abort there (a failed allocation: exceptions are not
  // compiled in) leaves the instance unusable, so it becomes out_of_memory from then on.
  _call(fn, fallback) {
    if (this._dead) return fallback;
    if (!this._ptr) throw new Error('pmz: decoder used after dispose()');
    try {
      return fn(this._m);
    } catch (e) {
      this._dead = 'pmz: out of memory: ' + String(e && e.message ? e.message : e).split('\n')[0];
      // The next createDecoder() gets a fresh instance.
      if (this._workers > 1) threadedModules.delete(this._workers); else modulePromise = null;
      return fallback;
    }
  }

  // Room for n input bytes in the heap (false when out of memory).
  _reserveInput(m, n) {
    if (this._inputSize < n) {
      m._free(this._input);
      this._inputSize = Math.max(n, 4096);
      this._input = m._malloc(this._inputSize);
      if (!this._input) { this._inputSize = 0; return false; }
    }
    return true;
  }

  feed(bytes) {
    if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
    let status = this._call((m) => m._pmz_decoder_status(this._ptr), 7);
    for (let at = 0; status === 0 && at < bytes.length; at += FEED_SLICE) {
      const piece = bytes.subarray(at, Math.min(bytes.length, at + FEED_SLICE));
      status = this._call((m) => {
        if (!this._reserveInput(m, piece.length)) return 7;
        m.HEAPU8.set(piece, this._input);
        return m._pmz_decoder_feed(this._ptr, this._input, piece.length);
      }, 7);
    }
    return STATUS_NAMES[status] ?? 'corrupt';
  }

  finish() {
    return STATUS_NAMES[this._call((m) => m._pmz_decoder_finish(this._ptr), 7)] ?? 'corrupt';
  }
  get status() {
    return STATUS_NAMES[this._call((m) => m._pmz_decoder_status(this._ptr), 7)] ?? 'corrupt';
  }
  get error() {
    if (this._dead) return this._dead;
    return this._call((m) => cString(m, m._pmz_decoder_error(this._ptr)), this._dead);
  }

  // In calls of at most REFINE_BATCH splits: V8 runs a wasm function's first calls in its
  // baseline tier and swaps in the optimized code only for later calls (there is no on-stack
  // replacement for wasm), so one call refining a whole mesh stays in baseline code throughout.
  // With workers, the batches double from there: the decoder hands a level's nodes to its
  // threads only as far as the call's splits reach whole nodes.
  refine(maxSplits) {
    const want = toU64(maxSplits);
    let total = 0n, size = REFINE_BATCH;
    this._call((m) => {
      while (total < want) {
        const batch = want - total < size ? want - total : size;
        const n = m._pmz_decoder_refine(this._ptr, batch);
        total += n;
        if (n < batch) break;
        if (this._workers > 1) size *= 2n;
      }
    });
    return Number(total);
  }
  coarsen(maxSplits) {
    return Number(this._call((m) => m._pmz_decoder_coarsen(this._ptr, toU64(maxSplits)), 0n));
  }
  setFaceTarget(faces) {
    this._call((m) => m._pmz_decoder_set_face_target(this._ptr, toU64(faces)));
  }
  setSplitTarget(splits) {
    this._call((m) => m._pmz_decoder_set_split_target(this._ptr, toU64(splits)));
  }

  get faceCount() { return this._call((m) => m._pmz_decoder_face_count(this._ptr) >>> 0, 0); }
  get vertexCount() {
    return this._call((m) => m._pmz_decoder_vertex_count(this._ptr) >>> 0, 0);
  }
  get splitsApplied() {
    return Number(this._call((m) => m._pmz_decoder_splits_applied(this._ptr), 0n));
  }
  get splitsAvailable() {
    return Number(this._call((m) => m._pmz_decoder_splits_available(this._ptr), 0n));
  }
  get bytesConsumed() {
    return Number(this._call((m) => m._pmz_decoder_bytes_consumed(this._ptr), 0n));
  }
  get complete() { return this.info().complete; }

  // The header's fields (valid once headerDone) and progress: pmz_stream_info.
  info() {
    return this._call((m) => {
      const s = this._scratch;
      m._pmz_decoder_info(this._ptr, s);
      const v = new DataView(m.HEAPU8.buffer, s, 104);
      const u64 = (o) => Number(v.getBigUint64(o, true));
      const u32 = (o) => v.getUint32(o, true);
      const f32 = (o) => v.getFloat32(o, true);
      return {
        baseVertices: u64(0), baseFaces: u64(8), fullVertices: u64(16), fullFaces: u64(24),
        totalSplits: u64(32), headerDone: u32(40) !== 0, baseDone: u32(44) !== 0,
        complete: u32(48) !== 0, versionMajor: u32(52), versionMinor: u32(56), flags: u32(60),
        positionBits: u32(64), curvature: u32(68), fineCurvature: u32(72),
        bboxMin: [f32(76), f32(80), f32(84)], bboxMax: [f32(88), f32(92), f32(96)],
        level: u32(100),
      };
    }, { headerDone: false, baseDone: false, complete: false });
  }

  // Zero-copy views into the WebAssembly heap: valid until the next call that changes the
  // mesh or feeds bytes (the heap may grow and the decoder's buffers move). Copy to keep.
  positions() {
    return this._call((m) => new Float32Array(m.HEAPU8.buffer,
      m._pmz_decoder_positions(this._ptr), 3 * this.vertexCount), new Float32Array(0));
  }
  indices() {
    return this._call((m) => new Uint32Array(m.HEAPU8.buffer,
      m._pmz_decoder_indices(this._ptr), 3 * this.faceCount), new Uint32Array(0));
  }
  // For geomorphs: the vertex each vertex was split from (0xFFFFFFFF for base vertices).
  splitParents() {
    return this._call((m) => new Uint32Array(m.HEAPU8.buffer,
      m._pmz_decoder_split_parents(this._ptr), this.vertexCount), new Uint32Array(0));
  }

  // Attributes (format 8.0): a render vertex is an attribute wedge (one combination of
  // texture coordinates, normal and colour at one position vertex). Without attributes in the
  // stream (or before the base mesh) wedgeCount is 0 and the views below are empty. The views
  // are zero-copy like positions(), valid until the next call that changes the mesh.
  get wedgeCount() { return this._call((m) => m._pmz_decoder_wedge_count(this._ptr) >>> 0, 0); }
  get texcoordSetCount() {
    return this._call((m) => m._pmz_decoder_texcoord_set_count(this._ptr) >>> 0, 0);
  }
  get colorComponents() {  // 0, 3 or 4
    return this._call((m) => m._pmz_decoder_color_components(this._ptr) >>> 0, 0);
  }
  get materialCount() {
    return this._call((m) => m._pmz_decoder_material_count(this._ptr) >>> 0, 0);
  }
  // A view of `per` elements per item over `count` items at the pointer fn returns (empty for
  // a null pointer).
  _view(Type, fn, per, count) {
    return this._call((m) => {
      const ptr = fn(m);
      return ptr ? new Type(m.HEAPU8.buffer, ptr, per * count) : new Type(0);
    }, new Type(0));
  }
  wedgeVertices() {  // wedge -> position vertex index
    return this._view(Uint32Array, (m) => m._pmz_decoder_wedge_vertices(this._ptr), 1, this.wedgeCount);
  }
  wedgePositions() {  // xyz per wedge: positions() of wedgeVertices()
    return this._view(Float32Array, (m) => m._pmz_decoder_wedge_positions(this._ptr), 3, this.wedgeCount);
  }
  wedgeIndices() {  // three wedges per face: the corners of indices()
    return this._view(Uint32Array, (m) => m._pmz_decoder_wedge_indices(this._ptr), 3,
                      this.wedgeCount ? this.faceCount : 0);
  }
  texcoords(set = 0) {  // u, v per wedge (v up, as in OBJ)
    if (!(set >= 0 && set < this.texcoordSetCount)) return new Float32Array(0);
    return this._view(Float32Array, (m) => m._pmz_decoder_texcoords(this._ptr, set >>> 0), 2,
                      this.wedgeCount);
  }
  normals() {  // unit xyz per wedge
    return this._view(Float32Array, (m) => m._pmz_decoder_normals(this._ptr), 3, this.wedgeCount);
  }
  colors() {  // colorComponents floats per wedge
    return this._view(Float32Array, (m) => m._pmz_decoder_colors(this._ptr), this.colorComponents,
                      this.wedgeCount);
  }
  faceMaterials() {  // per face an index into materials()
    return this._view(Uint32Array, (m) => m._pmz_decoder_face_materials(this._ptr), 1, this.faceCount);
  }
  // The material table as the file states it: {name, baseColor: [r, g, b, a],
  // baseColorTexture, normalTexture} (texture file names or URIs, '' when none).
  materials() {
    return this._call((m) => {
      const out = [], s = this._scratch;
      for (let i = 0; m._pmz_decoder_material(this._ptr, i, s); ++i) {
        const v = new DataView(m.HEAPU8.buffer, s, 28);
        out.push({
          name: cString(m, v.getUint32(0, true)),
          baseColorTexture: cString(m, v.getUint32(4, true)),
          normalTexture: cString(m, v.getUint32(8, true)),
          baseColor: [0, 1, 2, 3].map((k) => v.getFloat32(12 + 4 * k, true)),
        });
      }
      return out;
    }, []);
  }

  // What changed since the last clearChanges(), for partial GPU uploads: vertices
  // [vertexBegin, vertexCount) and faces [faceBegin, faceCount) are new or rewritten,
  // modifiedFaces (a heap view, may repeat) lists rewritten faces below faceBegin; all asks
  // for a full upload. Wedges [wedgeBegin, wedgeCount) are new; a face's wedgeIndices() and
  // faceMaterials() entries change exactly when its indices() do.
  changes() {
    return this._call((m) => {
      const s = this._scratch;
      m._pmz_decoder_changes(this._ptr, s);
      const v = new DataView(m.HEAPU8.buffer, s, 24);
      return {
        vertexBegin: v.getUint32(0, true),
        faceBegin: v.getUint32(4, true),
        modifiedFaces: new Uint32Array(m.HEAPU8.buffer, v.getUint32(8, true), v.getUint32(12, true)),
        all: v.getUint32(16, true) !== 0,
        wedgeBegin: v.getUint32(20, true),
      };
    }, { vertexBegin: 0, faceBegin: 0, modifiedFaces: new Uint32Array(0), all: true, wedgeBegin: 0 });
  }
  clearChanges() { this._call((m) => m._pmz_decoder_clear_changes(this._ptr)); }

  // Applies available splits for at most budgetMs (in batches that adapt to the rate seen),
  // and at most maxSplits of them. Returns the splits applied. After an error (a truncated or
  // damaged stream) the splits that arrived before the damage are still applied, as refine()
  // does (pmz-decode --salvage's level); 0 once none is left to apply.
  refineFor(budgetMs = 8, maxSplits = Infinity) {
    const start = performance.now();
    let total = 0, batch = this._batch || 256;
    for (;;) {
      const t0 = performance.now();
      const want = Math.min(batch, maxSplits - total);
      const n = this.refine(want);
      total += n;
      const now = performance.now();
      if (n < want || total >= maxSplits) break;
      const per = (now - t0) / n;
      // Aim each batch at a quarter of the budget left.
      batch = Math.max(16, Math.min(1 << 20, Math.floor((budgetMs - (now - start)) / 4 / (per || 1e-4))));
      this._batch = batch;
      if (now - start >= budgetMs) break;
    }
    return total;
  }

  // ---- View-dependent decoding (streams with a node table; pmz.h's pmz_decoder_update_view
  // and its neighbours, pmz/decoder.hpp states the contract). Feed the stream in order up to
  // its node table (nodeRange(1) is not null once it arrived), then updateView(view) each
  // frame: nodesToFetch() lists the nodes the view needs whose bytes are missing, nodeRange(k)
  // where they are in the file, feedNode(k, bytes) takes exactly those bytes. Streams without
  // a node table (or with attributes) refine in file order: nodesToFetch() stays empty.

  // view: {eye: [x, y, z], viewProjection: 16 numbers (column-major clip-from-mesh, three.js's
  // projectionMatrix x matrixWorldInverse x the mesh's matrixWorld), fovY (radians),
  // viewportHeight (pixels), pixelError}; eye in the mesh's own coordinates. Applies and undoes
  // whole nodes until about maxSplits splits (all when absent); returns the splits applied or
  // undone.
  updateView(view, maxSplits) {
    return Number(this._call((m) => {
      const v = new DataView(m.HEAPU8.buffer, this._scratch, VIEW_BYTES);
      for (let i = 0; i < 3; ++i) v.setFloat32(4 * i, view.eye[i], true);
      for (let i = 0; i < 16; ++i) v.setFloat32(12 + 4 * i, view.viewProjection[i], true);
      v.setFloat32(76, view.fovY ?? Math.PI / 3, true);
      v.setUint32(80, Math.max(1, Math.round(view.viewportHeight ?? 1080)), true);
      v.setFloat32(84, view.pixelError ?? 1, true);
      return m._pmz_decoder_update_view(this._ptr, this._scratch, toU64(maxSplits));
    }, 0n));
  }
  // A face budget for the nodes updateView() applies, from the next call on (0, null or
  // absent: none; pmz_decoder_set_view_face_budget, pmz/decoder.hpp states the contract): the
  // view's nodes largest projected error first, each with its parents, as long as the mesh's
  // faces stay within it; nodesToFetch() lists and viewComplete() waits for those only, and
  // applied nodes it no longer admits are undone. Node 0 is always applied.
  setViewFaceBudget(faces) {
    this._call((m) => m._pmz_decoder_set_view_face_budget(this._ptr, toU64(faces ?? 0)), undefined);
  }
  // After updateView(): every node the view needs (within the face budget) is applied (a stream
  // refined in file order: every split is).
  viewComplete() { return this._call((m) => m._pmz_decoder_view_complete(this._ptr) !== 0, false); }
  // After updateView(): the ids of the nodes the view needs (within the face budget) whose
  // bytes are missing, parents first, the largest projected error first (an Array).
  nodesToFetch() {
    return this._call((m) => {
      const ptr = m._pmz_decoder_nodes_to_fetch(this._ptr, this._scratch);
      const n = new DataView(m.HEAPU8.buffer, this._scratch, 4).getUint32(0, true);
      return n ? Array.from(new Uint32Array(m.HEAPU8.buffer, ptr, n)) : [];
    }, []);
  }
  // Node k's bytes in the file: {offset, size}, or null before the node table arrived or for k
  // out of range (node 0's bytes lie before the table: read in order).
  nodeRange(k) {
    return this._call((m) => {
      if (!(k >= 0 && k <= 0xffffffff) || !m._pmz_decoder_node_range(this._ptr, k >>> 0,
                                                                    this._scratch, this._scratch + 8))
        return null;
      const v = new DataView(m.HEAPU8.buffer, this._scratch, 16);
      return { offset: Number(v.getBigUint64(0, true)), size: Number(v.getBigUint64(8, true)) };
    }, null);
  }
  // The nodes in the table: 0 before it arrived (or when it holds node 0 alone).
  get nodeCount() {
    if (this._nodes) return this._nodes;
    if (!this.nodeRange(1)) return 0;
    let lo = 1, hi = 2;  // nodeRange(lo) is a range, nodeRange(hi) not yet known
    while (this.nodeRange(hi)) { lo = hi; hi *= 2; }
    while (hi - lo > 1) {
      const mid = Math.floor((lo + hi) / 2);
      if (this.nodeRange(mid)) lo = mid; else hi = mid;
    }
    return (this._nodes = lo + 1);
  }
  // Node k's bytes, exactly nodeRange(k)'s; a status as feed() returns (a node that arrived
  // already is ignored: 'ok'; wrong bytes fail the stream, the mesh stays valid).
  feedNode(k, bytes) {
    if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
    let status = this._call((m) => m._pmz_decoder_status(this._ptr), 7);
    if (status === 0) {
      status = this._call((m) => {
        if (!this._reserveInput(m, bytes.length)) return 7;
        m.HEAPU8.set(bytes, this._input);
        return m._pmz_decoder_feed_node(this._ptr, k >>> 0, this._input, bytes.length);
      }, 7);
    }
    return STATUS_NAMES[status] ?? 'corrupt';
  }
  // Nodes whose splits are in the mesh (node 0 included).
  nodesApplied() { return this._call((m) => m._pmz_decoder_nodes_applied(this._ptr) >>> 0, 0); }
  // A view for a camera at eye looking at target (y up): pmz_view_look_at. options: fovY
  // (radians, default 60 degrees), width, height (pixels, 1920 x 1080), near (1e-4),
  // pixelError (1). The same view pmz-decode --camera makes.
  lookAt(eye, target, options = {}) {
    const { fovY = Math.PI / 3, width = 1920, height = 1080, near = 1e-4, pixelError = 1 } = options;
    return this._call((m) => {
      const s = this._scratch, at = s + VIEW_BYTES;
      const v = new DataView(m.HEAPU8.buffer, s, 128);
      for (let i = 0; i < 3; ++i) {
        v.setFloat32(VIEW_BYTES + 4 * i, eye[i], true);
        v.setFloat32(VIEW_BYTES + 12 + 4 * i, target[i], true);
      }
      m._pmz_view_look_at(s, at, at + 12, fovY, width >>> 0, height >>> 0, near, pixelError);
      const r = new DataView(m.HEAPU8.buffer, s, VIEW_BYTES);
      const f = (o) => r.getFloat32(o, true);
      return { eye: [f(0), f(4), f(8)], viewProjection: Array.from({ length: 16 }, (_, i) => f(12 + 4 * i)),
        fovY: f(76), viewportHeight: r.getUint32(80, true), pixelError: f(84) };
    }, null);
  }

  dispose() {
    if (!this._ptr) return;
    if (!this._dead) {
      try {
        this._m._pmz_decoder_destroy(this._ptr);
        this._m._free(this._input);
        this._m._free(this._scratch);
      } catch (e) { /* the instance aborted meanwhile: nothing left to free */ }
    }
    this._ptr = 0;
  }
}

// A new decoder. options: maxVertices, maxFaces (0: the library's defaults), wasmBinary (the
// .wasm bytes, when the default location cannot be fetched: the single-threaded module, one
// worker), workers (threads decoding a stream's ready nodes at once; default the cores:
// navigator.hardwareConcurrency, node's os.availableParallelism()). More than one takes the
// threaded module where shared memory is available (node; browsers: cross-origin-isolated
// pages), else the single-threaded one: Decoder.workers says which. The mesh, ids, change
// reports and errors are the same whatever the workers.
export async function createDecoder(options = {}) {
  let workers = options.workers ?? await defaultWorkers();
  workers = Number.isFinite(workers) && workers >= 1 ? Math.min(Math.floor(workers), 64) : 1;
  return new Decoder(await loadModuleFor(workers, options), options);
}

// Feeds a ReadableStream (e.g. fetch()'s response.body) into the decoder as it arrives, then
// finish(). onData(bytesSoFar) runs after each slice; the caller refines (e.g. refineFor() per
// animation frame). Resolves to 'ok' or the error name; stops reading at the first error.
export async function feedStream(decoder, stream, onData) {
  const reader = stream.getReader();
  let bytes = 0;
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      bytes += value.length;
      const status = decoder.feed(value);
      if (onData) onData(bytes);
      if (status !== 'ok') return status;
    }
  } finally {
    reader.releaseLock();
  }
  return decoder.finish();
}

// fetch(url) streamed into the decoder: onData(bytes, totalBytes) with totalBytes from
// Content-Length (0 when unknown). Resolves to 'ok' or the error name; rejects when the
// request itself fails (network error, HTTP status other than 2xx).
export async function fetchInto(decoder, url, onData, init) {
  const response = await fetch(url, init);
  if (!response.ok) throw new Error(`pmz: ${url}: HTTP ${response.status}`);
  const total = Number(response.headers.get('content-length')) || 0;
  return feedStream(decoder, response.body, (bytes) => onData && onData(bytes, total));
}

// Reading a stream by byte ranges for view-dependent decoding (range_source.js).
export { RangeSource, loadView } from './range_source.js';
