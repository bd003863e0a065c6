// three.js loader for pmz: a BufferGeometry updated in place as the stream arrives and refines.
// Only the changed ranges are uploaded (BufferAttribute.addUpdateRange, three r159+).
import { Box3, BufferAttribute, BufferGeometry, Loader, Sphere, Vector3 } from 'three';
import { createDecoder, feedStream } from './index.js';

const RUNS_MAX = 64;  // more rewritten-face runs than this upload as one span
const MODIFIED_LIST_MAX = 1 << 16;  // rewritten faces listed per frame; more: one span

// Update ranges for rewritten faces: sorted runs, or one span when there are many.
function addFaceRuns(index, modifiedFaces) {
  const faces = Uint32Array.from(modifiedFaces).sort();
  const runs = [];
  for (const f of faces) {
    const last = runs[runs.length - 1];
    if (last && f <= last[1]) last[1] = Math.max(last[1], f + 1);
    else runs.push([f, f + 1]);
  }
  if (runs.length > RUNS_MAX) runs.splice(0, runs.length, [runs[0][0], runs[runs.length - 1][1]]);
  for (const [a, b] of runs) index.addUpdateRange(3 * a, 3 * (b - a));
}

// Index, position and (optional) pmzMorph attributes with room for what is needed, grown 4x at
// a time up to the header's full counts, contents kept. Not the full mesh at once: a new
// attribute is uploaded whole, and the first frame of a 1.2M-face stream then moved 31 MB
// (3.9 s to the first frame in SwiftShader).
function allocateGeometry(g, info, vertices, faces, caps, geomorph) {
  const room = (need, cap, full, least) =>
    Math.max(need, Math.min(Math.max(full, need), Math.max(4 * cap, 2 * need, least)));
  const vcap = room(vertices, caps.vertices, info.fullVertices, 1 << 15);
  const fcap = room(faces, caps.faces, info.fullFaces, 1 << 16);
  const grow = (name, old, size, itemSize, Type) => {
    const a = new BufferAttribute(new Type(size * itemSize), itemSize);
    if (old) a.array.set(old.array.subarray(0, Math.min(old.array.length, a.array.length)));
    if (name) g.setAttribute(name, a);
    return a;
  };
  if (vertices > caps.vertices) {
    grow('position', g.getAttribute('position'), vcap, 3, Float32Array);
    if (geomorph) grow('pmzMorph', g.getAttribute('pmzMorph'), vcap, 4, Float32Array);
    caps.vertices = vcap;
  }
  if (faces > caps.faces) {
    g.setIndex(grow(null, g.getIndex(), 3 * fcap, 1, Uint32Array));  // itemSize 1: three counts indices
    caps.faces = fcap;
  }
  const box = new Box3(new Vector3(...info.bboxMin), new Vector3(...info.bboxMax));
  g.boundingBox = box;
  g.boundingSphere = box.getBoundingSphere(new Sphere());
}

// The geometry of one stream and the decoder behind it. update() each animation frame.
export class PMZStream {
  constructor(decoder, options = {}) {
    this.decoder = decoder;
    this.geometry = new BufferGeometry();
    this.geomorph = options.geomorph ?? false;
    this.frameBudgetMs = options.frameBudgetMs ?? 8;
    this.faceTarget = null;  // null: follow the stream to its finest level
    this.bytes = 0;
    this.totalBytes = 0;
    this.status = 'ok';
    this.complete = false;  // see update()
    this._finished = false;
    this._vertexCap = 0;
    this._faceCap = 0;
    this._shownVertices = 0;
    this._clock = typeof performance === 'object' ? performance : Date;
  }

  get error() { return this.status === 'ok' ? '' : this.decoder.error; }
  get faceCount() { return this.decoder.faceCount; }
  get vertexCount() { return this.decoder.vertexCount; }
  get splitsApplied() { return this.decoder.splitsApplied; }
  info() { return this.decoder.info(); }
  // The decoder's current mesh (copies), e.g. to check the geometry against.
  async snapshot() {
    return { positions: this.decoder.positions().slice(), indices: this.decoder.indices().slice() };
  }

  feed(bytes) {
    this.bytes += bytes.length;
    if (this.status === 'ok') this.status = this.decoder.feed(bytes);
    return this.status;
  }
  finish() {
    if (this.status === 'ok') this.status = this.decoder.finish();
    this._finished = true;
    return this.status;
  }

  // Moves the level toward the target within frameBudgetMs and copies what changed into the
  // geometry. Returns true when the geometry changed.
  update(budgetMs = this.frameBudgetMs) {
    const d = this.decoder;
    if (!d.info().baseDone) return false;
    if (this.faceTarget === null) {
      d.refineFor(budgetMs);
    } else if (this.faceTarget !== d.faceCount) {
      d.setFaceTarget(this.faceTarget);
    }
    if (this.status === 'ok' && d.status !== 'ok') this.status = d.status;
    // Complete: every byte decoded and, when following the stream, the finest level shown.
    this.complete = this._finished && this.status === 'ok' &&
      (this.faceTarget !== null || d.splitsApplied === d.info().totalSplits);
    return this._sync();
  }

  _allocate(vertices, faces) {
    const caps = { vertices: this._vertexCap, faces: this._faceCap };
    allocateGeometry(this.geometry, this.decoder.info(), vertices, faces, caps, this.geomorph);
    this._vertexCap = caps.vertices;
    this._faceCap = caps.faces;
  }

  _sync() {
    const d = this.decoder, g = this.geometry;
    const nv = d.vertexCount, nf = d.faceCount;
    const c = d.changes();
    let all = c.all;
    if (nv > this._vertexCap || nf > this._faceCap) {
      this._allocate(nv, nf);
      all = true;
    }
    const pos = g.getAttribute('position'), index = g.getIndex();
    const vb = all ? 0 : c.vertexBegin, fb = all ? 0 : c.faceBegin;
    let changed = false;
    if (vb < nv) {
      const p = d.positions();
      pos.array.set(p.subarray(3 * vb, 3 * nv), 3 * vb);
      pos.addUpdateRange(3 * vb, 3 * (nv - vb));
      pos.needsUpdate = true;
      if (this.geomorph) this._morph(Math.max(vb, this._shownVertices), nv, all);
      changed = true;
    }
    const t = d.indices();
    if (fb < nf) {
      index.array.set(t.subarray(3 * fb, 3 * nf), 3 * fb);
      index.addUpdateRange(3 * fb, 3 * (nf - fb));
      changed = true;
    }
    if (!all && c.modifiedFaces.length) {
      for (const f of c.modifiedFaces) index.array.set(t.subarray(3 * f, 3 * f + 3), 3 * f);
      addFaceRuns(index, c.modifiedFaces);
      changed = true;
    }
    if (changed) index.needsUpdate = true;
    if (nf !== g.drawRange.count / 3) {
      g.setDrawRange(0, 3 * nf);
      changed = true;
    }
    this._shownVertices = nv;
    d.clearChanges();
    return changed;
  }

  // New vertices start at their parent's position and glide to their own (see
  // geomorphMaterial): pmzMorph = parent xyz, birth time in seconds.
  _morph(from, to, all) {
    const morph = this.geometry.getAttribute('pmzMorph');
    const p = this.decoder.positions(), parents = this.decoder.splitParents();
    const now = all ? -1e6 : this._clock.now() / 1000;
    for (let v = from; v < to; ++v) {
      const u = parents[v];
      const src = u === 0xffffffff || all ? v : u;
      morph.array[4 * v] = p[3 * src];
      morph.array[4 * v + 1] = p[3 * src + 1];
      morph.array[4 * v + 2] = p[3 * src + 2];
      morph.array[4 * v + 3] = now;
    }
    if (to > from) {
      morph.addUpdateRange(4 * from, 4 * (to - from));
      morph.needsUpdate = true;
    }
  }

  dispose() {
    this.decoder.dispose();
    this.geometry.dispose();
  }
}

// The same geometry decoded in a Web Worker (worker.js): the page only copies the changed
// ranges the worker posts into the geometry, so decoding never blocks a frame. update() each
// animation frame applies what arrived since the last one (budgetMs is not needed here).
export class PMZWorkerStream {
  constructor(options = {}) {
    this.geometry = new BufferGeometry();
    this.geomorph = options.geomorph ?? false;
    this.faceTarget = null;
    this.bytes = 0;
    this.totalBytes = 0;
    this.status = 'ok';
    this.complete = false;
    this.faceCount = 0;
    this.vertexCount = 0;
    this.splitsApplied = 0;
    this._error = '';
    this._info = { headerDone: false, baseDone: false, complete: false };
    this._caps = { vertices: 0, faces: 0 };
    this._pending = [];
    this._sentTarget = null;
    this._snapshots = new Map();
    this.firstBytesTime = null;
    this._clock = typeof performance === 'object' ? performance : Date;
    const { worker: _, ...cloneable } = options;
    this.worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
    this.worker.postMessage({ type: 'init', options: cloneable });
    let settle;
    this.done = new Promise((resolve, reject) => { settle = { resolve, reject }; });
    this.worker.onmessage = (e) => {
      const m = e.data;
      if (m.type === 'update') {
        this._pending.push(m);
        // When the first body bytes reached the worker, on this page's clock.
        if (this.firstBytesTime === null && m.firstBytesAt !== null)
          this.firstBytesTime = m.firstBytesAt - performance.timeOrigin;
        this.bytes = m.bytes;
        this.totalBytes = m.totalBytes || this.totalBytes;
      } else if (m.type === 'done') {
        this._done = m;
        settle.resolve(m.status);
      } else if (m.type === 'snapshot') {
        this._snapshots.get(m.id)(m);
        this._snapshots.delete(m.id);
      } else if (m.type === 'failed') {
        settle.reject(new Error(m.error));
      }
    };
    this.worker.onerror = (e) => settle.reject(new Error(`pmz: worker: ${e.message}`));
  }

  get error() { return this.status === 'ok' ? '' : this._error; }
  info() { return this._info; }
  // The worker's current mesh (copies), e.g. to check the geometry against.
  snapshot() {
    const id = this._snapshots.size + Math.random();
    return new Promise((resolve) => {
      this._snapshots.set(id, resolve);
      this.worker.postMessage({ type: 'snapshot', id });
    });
  }

  open(source, init) {
    if (typeof source === 'string' || source instanceof URL)
      this.worker.postMessage({ type: 'open', url: new URL(source, location.href).href, init });
    else if (source && typeof source.stream === 'function')  // Blob, File
      this.worker.postMessage({ type: 'open', blob: source });
  }
  // Bytes read on the page (a Response or a ReadableStream), passed on to the worker.
  feed(bytes) {
    const copy = bytes.slice();
    this.worker.postMessage({ type: 'feed', bytes: copy }, [copy.buffer]);
    return this.status;
  }
  finish() {
    this.worker.postMessage({ type: 'finish' });
    return this.status;
  }

  // Applies the worker's updates that arrived since the last call. True when the geometry
  // changed.
  update() {
    if (this.faceTarget !== this._sentTarget) {
      this._sentTarget = this.faceTarget;
      this.worker.postMessage({ type: 'target', faces: this.faceTarget });
    }
    const g = this.geometry;
    let changed = false, vmin = Infinity, vmax = 0, fmin = Infinity, fmax = 0, mmin = Infinity;
    const modified = [];  // rewritten faces, or with manyModified only their span
    let modMin = Infinity, modMax = -1, manyModified = false;
    for (const m of this._pending) {
      Object.assign(this, { faceCount: m.faces, vertexCount: m.vertices,
        splitsApplied: m.splitsApplied, status: m.status });
      this._error = m.error;
      this._info = m.info;
      if (!m.positions) continue;
      let all = m.all;
      if (m.vertices > this._caps.vertices || m.faces > this._caps.faces) {
        if (this._caps.faces) all = true;  // reallocated: whatever came before is in, kept
        allocateGeometry(g, m.info, m.vertices, m.faces, this._caps, this.geomorph);
        vmin = 0; vmax = Math.max(vmax, m.vertices); fmin = 0; fmax = Math.max(fmax, m.faces);
      }
      g.getAttribute('position').array.set(m.positions, 3 * m.vertexBegin);
      g.getIndex().array.set(m.indices, 3 * m.faceBegin);
      vmin = Math.min(vmin, m.vertexBegin); vmax = Math.max(vmax, m.vertices);
      fmin = Math.min(fmin, m.faceBegin); fmax = Math.max(fmax, m.faces);
      if (all) { vmin = 0; fmin = 0; }
      if (m.modified) {  // (face, a, b, c); element copies: a subarray per face was seconds
        const index = g.getIndex().array, mm = m.modified;
        for (let i = 0; i < mm.length; i += 4) {
          const f = mm[i];
          index[3 * f] = mm[i + 1];
          index[3 * f + 1] = mm[i + 2];
          index[3 * f + 2] = mm[i + 3];
          if (f < modMin) modMin = f;
          if (f > modMax) modMax = f;
          if (modified.length < MODIFIED_LIST_MAX) modified.push(f);
          else manyModified = true;
        }
      }
      if (m.morph) {
        const morph = g.getAttribute('pmzMorph').array;
        const now = m.all ? -1e6 : this._clock.now() / 1000;
        for (let v = m.morphBegin, i = 0; v < m.vertices; ++v, i += 3) {
          morph[4 * v] = m.morph[i];
          morph[4 * v + 1] = m.morph[i + 1];
          morph[4 * v + 2] = m.morph[i + 2];
          morph[4 * v + 3] = now;
        }
        mmin = Math.min(mmin, m.morphBegin);
      }
      changed = true;
    }
    this._pending.length = 0;
    if (changed) {
      const pos = g.getAttribute('position'), index = g.getIndex();
      if (vmin < vmax) {
        pos.addUpdateRange(3 * vmin, 3 * (vmax - vmin));
        pos.needsUpdate = true;
        if (this.geomorph && Math.min(mmin, vmin) < vmax) {
          const morph = g.getAttribute('pmzMorph'), from = Math.min(mmin, vmin);
          morph.addUpdateRange(4 * from, 4 * (vmax - from));
          morph.needsUpdate = true;
        }
      }
      if (fmin < fmax) index.addUpdateRange(3 * fmin, 3 * (fmax - fmin));
      if (manyModified) index.addUpdateRange(3 * modMin, 3 * (modMax + 1 - modMin));
      else if (modified.length) addFaceRuns(index, modified);
      index.needsUpdate = true;
      g.setDrawRange(0, 3 * this.faceCount);
    }
    this.complete = !!this._done && this._done.status === 'ok' && this.status === 'ok' &&
      this._pending.length === 0 &&
      (this.faceTarget !== null || this.splitsApplied === this._info.totalSplits);
    return changed;
  }

  dispose() {
    this.worker.postMessage({ type: 'close' });
    this.geometry.dispose();
  }
}

// Patches a three.js material so new vertices glide from their parent's position over
// `seconds` (geometry from a PMZStream with geomorph: true). Call uniforms.pmzTime update via
// the returned function each frame.
export function geomorphMaterial(material, seconds = 0.4) {
  const uniforms = { pmzTime: { value: 0 }, pmzDuration: { value: seconds } };
  material.onBeforeCompile = (shader) => {
    Object.assign(shader.uniforms, uniforms);
    shader.vertexShader = shader.vertexShader
      .replace('#include <common>',
        '#include <common>\nattribute vec4 pmzMorph;\nuniform float pmzTime;\nuniform float pmzDuration;')
      .replace('#include <begin_vertex>',
        'vec3 transformed = mix(pmzMorph.xyz, position, ' +
        'clamp((pmzTime - pmzMorph.w) / pmzDuration, 0.0, 1.0));');
  };
  material.customProgramCacheKey = () => 'pmz-geomorph';
  const clock = typeof performance === 'object' ? performance : Date;
  const tick = () => { uniforms.pmzTime.value = clock.now() / 1000; };
  tick.uniforms = uniforms;  // pmzTime (seconds, performance.now() / 1000), pmzDuration
  return tick;
}

// three.js loader: load(url, onLoad, onProgress, onError) calls onLoad(geometry, stream) once
// the base mesh is in; the geometry keeps refining in place (stream.update() per animation
// frame, done here unless options.autoUpdate is false). stream(source) takes a URL, a
// Response, a ReadableStream or a Blob/File and resolves to the PMZStream at once; its .done
// resolves to the final status when every byte is fed.
export class PMZLoader extends Loader {
  constructor(manager, options = {}) {
    super(manager);
    this.options = options;
  }

  load(url, onLoad, onProgress, onError) {
    const resolved = this.manager.resolveURL(this.path + url);
    this.manager.itemStart(resolved);
    let loaded = false;
    const fail = (e) => {
      if (onError) onError(e);
      else console.error(e);
      this.manager.itemError(resolved);
      this.manager.itemEnd(resolved);
    };
    const onUpdate = (s) => {
      if (!loaded && s.info().baseDone) {
        loaded = true;
        if (onLoad) onLoad(s.geometry, s);
      }
      if (onProgress) onProgress({ loaded: s.bytes, total: s.totalBytes, stream: s });
    };
    this.stream(resolved, onUpdate).then((s) => s.done.then((status) => {
      if (status !== 'ok') throw new Error(s.error || `pmz: ${resolved}: ${status}`);
      this.manager.itemEnd(resolved);
    })).catch(fail);
  }

  loadAsync(url, onProgress) {
    return new Promise((resolve, reject) => this.load(url, resolve, onProgress, reject));
  }

  async stream(source, onUpdate) {
    const opts = this.options;
    const auto = opts.autoUpdate !== false && typeof requestAnimationFrame === 'function';
    const inWorker = opts.worker && typeof Worker === 'function';
    const s = inWorker ? new PMZWorkerStream(opts) : new PMZStream(await createDecoder(opts), opts);
    const tick = () => {
      s.update();
      if (onUpdate) onUpdate(s);
      if (!s.complete && s.status === 'ok') requestAnimationFrame(tick);
    };
    if (inWorker && (typeof source === 'string' || source instanceof URL ||
                     (source && typeof source.stream === 'function'))) {
      // The worker fetches or reads it itself.
      s.open(source, typeof source === 'string' || source instanceof URL ? {
        headers: this.requestHeader,
        credentials: this.withCredentials ? 'include' : 'same-origin',
      } : undefined);
      if (auto) requestAnimationFrame(tick);
      return s;
    }
    const workerDone = inWorker ? s.done : null;
    s.done = (async () => {
      let body = source;
      if (typeof source === 'string' || source instanceof URL) {
        const r = await fetch(source, {
          headers: this.requestHeader,
          credentials: this.withCredentials ? 'include' : 'same-origin',
        });
        if (!r.ok) throw new Error(`pmz: ${source}: HTTP ${r.status}`);
        source = r;
      }
      if (typeof Response !== 'undefined' && source instanceof Response) {
        s.totalBytes = Number(source.headers.get('content-length')) || 0;
        body = source.body;
      } else if (source && typeof source.stream === 'function') {  // Blob, File
        s.totalBytes = source.size;
        body = source.stream();
      }
      if (auto) requestAnimationFrame(tick);
      // Stops reading at the first error, which it resolves to.
      const status = await feedStream({ feed: (b) => s.feed(b), finish: () => s.finish() }, body,
                                      () => onUpdate && onUpdate(s));
      return workerDone ? workerDone : status;
    })();
    return s;
  }
}
