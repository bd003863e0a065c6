// SPDX-License-Identifier: MIT
// three.js loader for pmz: a BufferGeometry updated in place as the stream arrives and refines.
// Only the changed ranges are uploaded (BufferAttribute.addUpdateRange, three r159+). With
// attributes (format 8.0) a render vertex is an attribute wedge (as in the native viewer): uv,
// uv1, normal and color attributes beside position, and a group per run of faces of one
// material when the stream has several (pmzMaterials() makes the three.js materials).
import { Box3, BufferAttribute, BufferGeometry, Color, DataTexture, DoubleSide, LinearFilter,
  LinearMipmapLinearFilter, Loader, Matrix4, MeshStandardMaterial, RepeatWrapping, Sphere,
  SRGBColorSpace, TextureLoader, Vector3 } from 'three';
import { RangeSource, createDecoder, feedStream } from './index.js';
import { renderArrays, renderUpdate } from './render_update.js';

const RUNS_MAX = 64;  // more rewritten-face runs than this upload as one span
const MODIFIED_LIST_MAX = 1 << 16;  // rewritten faces listed per frame; more: one span

// The bytes of ranges a renderUpdate() carries (what applying it copies and uploads).
function renderBytes(u) {
  let n = u.positions.byteLength + u.indices.byteLength;
  for (const name in u.attributes) n += u.attributes[name].byteLength;
  for (const a of [u.faceMaterials, u.modified, u.morph]) if (a) n += a.byteLength;
  return n;
}

// Update ranges for rewritten faces: sorted runs, or one span when there are many.
function addFaceRuns(attributes, modifiedFaces, perFace) {
  const faces = Uint32Array.from(modifiedFaces).sort();
  const runs = [];
  for (const f of faces) {
    const last = runs[runs.length - 1];
    if (last && f <= last[1]) last[1] = Math.max(last[1], f + 1);
    else runs.push([f, f + 1]);
  }
  if (runs.length > RUNS_MAX) runs.splice(0, runs.length, [runs[0][0], runs[runs.length - 1][1]]);
  for (const [a, b] of runs) attributes.addUpdateRange(perFace * a, perFace * (b - a));
}

// Room for what is needed, contents kept: twice what is needed (at least a little, at most
// the header's full counts; render vertices with attributes: wedges, which the header does not
// count: 1.5x its vertices). Each growth uploads the new attribute whole, so small first: the
// first frame with the object uploads the base mesh's room only (bunny00's first object frame
// 107-196 ms with room for 32k vertices and 64k faces, 38-88 ms with this, load 16-20); and
// doubling rather than jumping to the full counts: a stream shown within a face limit until
// its end never uploads the full mesh's room before it has the full mesh (31 MB for 1.2M
// faces). Doubling uploads at most twice the final bytes in all.
function allocateGeometry(g, info, vertices, faces, caps, spec) {
  const room = (need, full, least) => Math.max(need, Math.min(full, Math.max(2 * need, least)));
  const fullVertices = spec.layout.length ? Math.ceil(1.5 * info.fullVertices) : info.fullVertices;
  const vcap = room(vertices, fullVertices, 256);
  const fcap = room(faces, info.fullFaces, 512);
  const grow = (name, old, size, itemSize, Type) => {
    const a = new BufferAttribute(new Type(size * itemSize), itemSize);
    if (old) a.array.set(old.array.subarray(0, Math.min(old.array.length, a.array.length)));
    if (name) g.setAttribute(name, a);
    return a;
  };
  if (vertices > caps.vertices) {
    grow('position', g.getAttribute('position'), vcap, 3, Float32Array);
    for (const [name, size] of spec.layout) grow(name, g.getAttribute(name), vcap, size, Float32Array);
    if (spec.geomorph) grow('pmzMorph', g.getAttribute('pmzMorph'), vcap, 4, Float32Array);
    caps.vertices = vcap;
  }
  if (faces > caps.faces) {
    g.setIndex(grow(null, g.getIndex(), 3 * fcap, 1, Uint32Array));  // itemSize 1: three counts indices
    if (spec.groups) {
      const m = new Uint32Array(fcap);
      m.set(spec.faceMaterials.subarray(0, Math.min(fcap, spec.faceMaterials.length)));
      spec.faceMaterials = m;
    }
    caps.faces = fcap;
  }
  const box = new Box3(new Vector3(...info.bboxMin), new Vector3(...info.bboxMax));
  g.boundingBox = box;
  g.boundingSphere = box.getBoundingSphere(new Sphere());
}

// A geometry kept equal to a decoder's render arrays by applying renderUpdate()s (views on the
// page, copies posted by the worker). The update ranges of all updates applied in one frame
// are merged.
class GeometryMirror {
  // flipV: texture coordinates as glTF's (v down the image: 1 - v of the stream's).
  constructor(geomorph, flipV = false) {
    this.geometry = new BufferGeometry();
    this.spec = { geomorph, flipV, layout: null, groups: false, faceMaterials: new Uint32Array(0) };
    this.caps = { vertices: 0, faces: 0 };
    this.faces = 0;
    this.clock = typeof performance === 'object' ? performance : Date;
  }

  // Applies the updates in order; true when the geometry changed.
  apply(updates, info) {
    const g = this.geometry, spec = this.spec;
    let vmin = Infinity, vmax = 0, fmin = Infinity, fmax = 0, mmin = Infinity;
    const modified = [];  // rewritten faces, or with manyModified only their span
    let modMin = Infinity, modMax = -1, manyModified = false, changed = false;
    let regroupFrom = Infinity;  // the first face whose material may have changed
    for (const u of updates) {
      if (!spec.layout) {
        spec.layout = u.layout;
        spec.groups = !!u.faceMaterials;
      }
      let all = u.all;
      if (u.count > this.caps.vertices || u.faces > this.caps.faces) {
        if (this.caps.faces) all = true;  // reallocated: whatever came before is in, kept
        allocateGeometry(g, info, u.count, u.faces, this.caps, spec);
        vmin = 0; vmax = Math.max(vmax, u.count); fmin = 0; fmax = Math.max(fmax, u.faces);
      }
      const vb = u.vertexBegin, fb = u.faceBegin;
      g.getAttribute('position').array.set(u.positions, 3 * vb);
      for (const [name, size] of spec.layout) {
        const a = g.getAttribute(name).array;
        a.set(u.attributes[name], size * vb);
        if (spec.flipV && size === 2)
          for (let i = 2 * vb + 1, end = 2 * u.count; i < end; i += 2) a[i] = 1 - a[i];
      }
      const index = g.getIndex().array;
      index.set(u.indices, 3 * fb);
      if (spec.groups && u.faceMaterials) spec.faceMaterials.set(u.faceMaterials, fb);
      vmin = Math.min(vmin, vb); vmax = Math.max(vmax, u.count);
      fmin = Math.min(fmin, fb); fmax = Math.max(fmax, u.faces);
      if (all) { vmin = 0; fmin = 0; }
      if (u.modified) {  // (face, a, b, c); element copies: a subarray per face was seconds
        const mm = u.modified;
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
        if (spec.groups && u.modifiedMaterials) {
          const fm = spec.faceMaterials;
          for (let i = 0; i < u.modifiedMaterials.length; ++i) {
            const f = mm[4 * i];
            if (fm[f] !== u.modifiedMaterials[i]) {
              fm[f] = u.modifiedMaterials[i];
              if (f < regroupFrom) regroupFrom = f;
            }
          }
        }
      }
      if (u.morph && spec.geomorph) {
        const morph = g.getAttribute('pmzMorph').array;
        const now = u.all ? -1e6 : this.clock.now() / 1000;
        for (let v = u.morphBegin, i = 0; v < u.count; ++v, i += 3) {
          morph[4 * v] = u.morph[i];
          morph[4 * v + 1] = u.morph[i + 1];
          morph[4 * v + 2] = u.morph[i + 2];
          morph[4 * v + 3] = now;
        }
        mmin = Math.min(mmin, u.morphBegin);
      }
      this.faces = u.faces;
      changed = true;
    }
    if (!changed) return false;
    if (vmin < vmax) {
      for (const name of ['position', ...spec.layout.map(([n]) => n)]) {
        const a = g.getAttribute(name);
        a.addUpdateRange(a.itemSize * vmin, a.itemSize * (vmax - vmin));
        a.needsUpdate = true;
      }
    }
    if (spec.geomorph && Math.min(mmin, vmin) < vmax) {
      const morph = g.getAttribute('pmzMorph'), from = Math.min(mmin, vmin);
      morph.addUpdateRange(4 * from, 4 * (vmax - from));
      morph.needsUpdate = true;
    }
    const index = g.getIndex();
    if (fmin < fmax) index.addUpdateRange(3 * fmin, 3 * (fmax - fmin));
    if (manyModified) index.addUpdateRange(3 * modMin, 3 * (modMax + 1 - modMin));
    else if (modified.length) addFaceRuns(index, modified, 3);
    index.needsUpdate = true;
    g.setDrawRange(0, 3 * this.faces);
    if (spec.groups) this._groups(Math.min(fmin, regroupFrom));
    return true;
  }

  // One group per run of faces of one material (materialIndex: the material table's index),
  // redone from face `from` on (the groups before it stand): new faces and the faces whose
  // material changed (a split rewrites a face's corners, rarely its material) only, not every
  // face on each update.
  _groups(from) {
    const g = this.geometry, m = this.spec.faceMaterials, nf = this.faces, groups = g.groups;
    let f = Math.min(from, nf);
    while (groups.length && groups[groups.length - 1].start >= 3 * f) groups.pop();
    const last = groups[groups.length - 1];
    if (last && last.start + last.count > 3 * f) last.count = 3 * f - last.start;
    while (f < nf) {
      const start = f, id = m[f];
      while (f < nf && m[f] === id) ++f;
      const prev = groups[groups.length - 1];
      if (prev && prev.materialIndex === id && prev.start + prev.count === 3 * start) prev.count += 3 * (f - start);
      else g.addGroup(3 * start, 3 * (f - start), id);
    }
  }
}

// Copies what changed in the decoder since the last call into the mirror's geometry, then
// clears the change report; true when the geometry changed.
function syncMirror(d, mirror, state, geomorph) {
  const u = renderUpdate(d, state, { geomorph });
  const c = d.changes();
  const nothing = !c.all && u.vertexBegin >= u.count && u.faceBegin >= u.faces && !u.modified &&
    u.faces === mirror.faces;
  const changed = !nothing && mirror.apply([u], d.info());
  d.clearChanges();
  return changed;
}

// The geometry of one stream and the decoder behind it. update() each animation frame.
export class PMZStream {
  constructor(decoder, options = {}) {
    this.decoder = decoder;
    this._mirror = new GeometryMirror(options.geomorph ?? false, options.flipV ?? false);
    this.geometry = this._mirror.geometry;
    this.geomorph = options.geomorph ?? false;
    this.frameBudgetMs = options.frameBudgetMs ?? 8;
    this.faceTarget = null;  // null: follow the stream to its finest level
    // Following the stream, at most this many faces shown until decoding ends (null: no limit;
    // see update()).
    this.faceLimit = options.faceLimit ?? null;
    this.bytes = 0;
    this.totalBytes = 0;
    this.status = 'ok';
    this.complete = false;  // see update()
    // Decoding ended (see update()): complete, or failed with what arrived before the damage
    // shown.
    this.ended = false;
    this._finished = false;
    this._stalled = false;  // failed, and refinement applies no more splits
    this._held = false;  // the geometry shows an older level than the decoder's (faceLimit)
    this._baseShown = false;
    this._shownVertices = 0;
    this._renderState = { shownVertices: 0 };
  }

  get error() { return this.status === 'ok' ? '' : this.decoder.error; }
  // The geometry's level (older than the decoder's while held back by faceLimit).
  get faceCount() { return this._held ? this._mirror.faces : this.decoder.faceCount; }
  get vertexCount() { return this._held ? this._shownVertices : this.decoder.vertexCount; }
  // The decoder's level (faceCount unless held back by faceLimit).
  get decodedFaces() { return this.decoder.faceCount; }
  get splitsApplied() { return this.decoder.splitsApplied; }
  info() { return this.decoder.info(); }
  // The material table ([] without materials): see Decoder.materials().
  materials() { return this.decoder.materials(); }
  // The decoder's current mesh (copies), e.g. to check the geometry against, and the render
  // arrays (render_update.js: the wedges' with attributes).
  async snapshot() {
    const d = this.decoder;
    return { positions: d.positions().slice(), indices: d.indices().slice(), render: renderArrays(d) };
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
  // geometry. Returns true when the geometry changed. The base mesh is shown before any
  // refinement. With faceLimit, following the stream: refinement goes up to the limit and,
  // while bytes arrive, waits there; once every byte is in it goes on, but the geometry keeps
  // the level at the limit until every split is applied, then shows the finest level at once.
  // A failed stream (truncated or damaged; status and error say why) is refined on the same
  // way up to what arrived before the damage (pmz-decode --salvage's level).
  update(budgetMs = this.frameBudgetMs) {
    const d = this.decoder;
    const info = d.info();
    if (this.status === 'ok' && d.status !== 'ok') this.status = d.status;
    // No more bytes come once finish() ran or feeding failed.
    const bytesEnded = this._finished || this.status !== 'ok';
    if (!info.baseDone) {
      this.ended = this.status !== 'ok';  // failed before the base mesh: nothing to show
      return false;
    }
    if (!this._baseShown) {  // the base mesh first, not refined yet
      this._baseShown = true;
      return this._sync();
    }
    if (this.faceTarget === null) {
      // Within the limit (a split adds at most two faces); past it once every byte is in.
      const within = this.faceLimit === null ? Infinity : Math.floor((this.faceLimit - d.faceCount) / 2);
      const room = within > 0 ? within : bytesEnded ? Infinity : 0;
      if (room > 0 && d.refineFor(budgetMs, room) === 0 && d.status !== 'ok') this._stalled = true;
    } else if (this.faceTarget !== d.faceCount) {
      d.setFaceTarget(this.faceTarget);
    }
    if (this.status === 'ok' && d.status !== 'ok') this.status = d.status;
    const allApplied = d.splitsApplied === info.totalSplits;
    // Complete: every byte decoded and, when following the stream, the finest level shown.
    this.complete = this._finished && this.status === 'ok' && (this.faceTarget !== null || allApplied);
    const failed = this.status !== 'ok';
    const decodingEnded = bytesEnded && (allApplied ||
                                         failed && (this._stalled || d.splitsApplied >= d.splitsAvailable));
    this.ended = this.complete || failed && (this.faceTarget !== null || decodingEnded);
    this._held = this.faceTarget === null && this.faceLimit !== null && d.faceCount > this.faceLimit &&
      !decodingEnded;
    return this._held ? false : this._sync();
  }

  _sync() {
    const changed = syncMirror(this.decoder, this._mirror, this._renderState, this.geomorph);
    this._shownVertices = this.decoder.vertexCount;
    return changed;
  }

  dispose() {
    this.decoder.dispose();
    this.geometry.dispose();
  }
}

// Decoder.updateView()'s view of a three.js camera for an object (its matrixWorld; null: the
// identity) drawn into a viewport viewportHeight pixels high: the eye in the object's own
// coordinates, projectionMatrix x matrixWorldInverse x matrixWorld, the effective vertical
// field of view (zoom included; perspective cameras).
export function cameraView(camera, object, viewportHeight, pixelError = 1) {
  camera.updateMatrixWorld();
  const m = new Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
  const eye = new Vector3().setFromMatrixPosition(camera.matrixWorld);
  if (object) {
    object.updateMatrixWorld();
    m.multiply(object.matrixWorld);
    eye.applyMatrix4(new Matrix4().copy(object.matrixWorld).invert());
  }
  const fov = camera.isPerspectiveCamera ? camera.getEffectiveFOV() : 60;
  return { eye: eye.toArray(), viewProjection: m.elements.slice(), fovY: fov * Math.PI / 180,
    viewportHeight, pixelError };
}

// A stream decoded for a camera (view-dependent decoding; streams with a node table): the
// stream's bytes in order up to its node table, then only the nodes the camera needs, fetched
// by ranges (RangeSource). update(camera, object?) each frame: builds the view from the camera
// and the object's world matrix (object defaults to this.object), moves the mesh towards it
// within frameBudgetMs, asks for the nodes still missing and uploads what changed. Faces of
// nodes not applied are degenerate (they draw nothing). A stream without a node table (or with
// attributes), or a server that ignores Range, is read in order and refined as it arrives.
export class PMZViewStream {
  constructor(decoder, url, options = {}) {
    this.decoder = decoder;
    this.url = String(url);
    this._mirror = new GeometryMirror(false, options.flipV ?? false);
    this.geometry = this._mirror.geometry;
    this.frameBudgetMs = options.frameBudgetMs ?? 8;
    this.pixelError = options.pixelError ?? 1;
    // A face budget (Decoder.setViewFaceBudget(), at each update(); 0 or null: none): the nodes
    // the view needs most, with their parents, as long as the mesh stays within maxFaces faces.
    this.maxFaces = options.maxFaces ?? 0;
    this.viewportHeight = options.viewportHeight ?? 1080;  // pixels: the renderer's drawing buffer
    this.object = null;  // the mesh drawing the geometry (its world matrix), when update() has none
    this.status = 'ok';
    this.complete = false;  // every node the last view needs is applied
    this.ended = false;  // failed (status, error say why)
    this._view = null;
    this._baseShown = false;
    this._renderState = { shownVertices: 0 };
    this._batch = 4096;
    this.source = new RangeSource(decoder, url, { init: options.init, inFlight: options.inFlight,
      timeoutMs: options.timeoutMs, firstBytes: options.firstBytes });
    // Resolves to the decoder's status once the in-order part is in (up to the node table, or
    // the whole stream without one); rejects on a failed request.
    this.done = this.source.open().then(() => this.decoder.status);
    this.done.catch(() => {});  // (kept in error too: a caller need not await done)
  }

  get error() {
    return this.source.error || (this.decoder.status === 'ok' ? '' : this.decoder.error);
  }
  get bytes() { return this.source.bytes; }
  get totalBytes() { return this.source.totalBytes; }
  get faceCount() { return this.decoder.faceCount; }
  get vertexCount() { return this.decoder.vertexCount; }
  get decodedFaces() { return this.decoder.faceCount; }
  get splitsApplied() { return this.decoder.splitsApplied; }
  get nodesApplied() { return this.decoder.nodesApplied(); }
  get nodeCount() { return this.decoder.nodeCount; }
  info() { return this.decoder.info(); }
  materials() { return this.decoder.materials(); }
  async snapshot() {
    const d = this.decoder;
    return { positions: d.positions().slice(), indices: d.indices().slice(), render: renderArrays(d) };
  }

  // Moves the mesh towards the camera's view within budgetMs (the last camera's without one),
  // fetches what it still needs and copies what changed into the geometry. True when the
  // geometry changed. The base mesh is shown before any refinement.
  update(camera, object = this.object, budgetMs = this.frameBudgetMs) {
    const d = this.decoder;
    if (camera) this._view = cameraView(camera, object, this.viewportHeight, this.pixelError);
    if (this.status === 'ok' && d.status !== 'ok') this.status = d.status;
    this.ended = this.status !== 'ok' || this.source.error !== '';  // (error says why)
    if (!d.info().baseDone) return false;
    if (!this._baseShown) {
      this._baseShown = true;
      return this._sync();
    }
    if (this._view && d.status === 'ok') {
      d.setViewFaceBudget(this.maxFaces);
      // Batches of splits sized to a quarter of the budget left, as refineFor() does.
      const start = performance.now();
      for (;;) {
        const t0 = performance.now();
        const n = d.updateView(this._view, this._batch);
        const now = performance.now();
        if (n === 0 || d.status !== 'ok') break;
        const per = (now - t0) / n;
        this._batch = Math.max(64, Math.min(1 << 20, Math.floor((budgetMs - (now - start)) / 4 / (per || 1e-4))));
        if (now - start >= budgetMs) break;
      }
      if (d.status === 'ok') this.source.want(d.nodesToFetch());
      this.complete = d.status === 'ok' && d.viewComplete();
    }
    return this._sync();
  }

  _sync() { return syncMirror(this.decoder, this._mirror, this._renderState, false); }

  dispose() {
    this.source.close();
    this.decoder.dispose();
    this.geometry.dispose();
  }
}

// The same geometry decoded in a Web Worker (worker.js): the page only copies the changed
// ranges the worker posts into the geometry, so decoding never blocks a frame. update() each
// animation frame applies what arrived since the last one (budgetMs is not needed here).
export class PMZWorkerStream {
  constructor(options = {}) {
    this._mirror = new GeometryMirror(options.geomorph ?? false, options.flipV ?? false);
    this.geometry = this._mirror.geometry;
    this.geomorph = options.geomorph ?? false;
    this.faceTarget = null;
    // Following the stream, at most this many faces shown until decoding ends (null: none;
    // see PMZStream.update()).
    this.faceLimit = options.faceLimit ?? null;
    // update() applies the worker's updates in order until about this many bytes of ranges
    // (at least one update): what one frame copies and uploads.
    this.maxUpdateBytes = options.maxUpdateBytes ?? 8 << 20;
    this.bytes = 0;
    this.totalBytes = 0;
    this.status = 'ok';
    this.complete = false;
    this.ended = false;  // as PMZStream's
    this.faceCount = 0;
    this.vertexCount = 0;
    this.decodedFaces = 0;
    this.splitsApplied = 0;
    this._error = '';
    this._info = { headerDone: false, baseDone: false, complete: false };
    this._materials = [];
    this._pending = [];
    this._sentTarget = null;
    this._sentLimit = this.faceLimit;  // in the init message
    this._snapshots = new Map();
    this.firstBytesTime = null;
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
        if (m.materials) this._materials = m.materials;
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
  // The material table ([] without materials, or before the base mesh).
  materials() { return this._materials; }
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
  // The worker stops refining for about ms, from the end of its current slice.
  pauseDecoding(ms) {
    this.worker.postMessage({ type: 'pause', ms });
  }

  // Applies the worker's updates that arrived since the last call, in order, up to
  // maxUpdateBytes of ranges (the rest waits for the next call). True when the geometry
  // changed.
  update() {
    if (this.faceTarget !== this._sentTarget) {
      this._sentTarget = this.faceTarget;
      this.worker.postMessage({ type: 'target', faces: this.faceTarget });
    }
    if (this.faceLimit !== this._sentLimit) {
      this._sentLimit = this.faceLimit;
      this.worker.postMessage({ type: 'limit', faces: this.faceLimit });
    }
    const updates = [];
    let taken = 0, size = 0;
    for (const m of this._pending) {
      if (m.render) {
        const bytes = renderBytes(m.render);
        if (updates.length && size + bytes > this.maxUpdateBytes) break;
        size += bytes;
        updates.push(m.render);
      }
      ++taken;
      Object.assign(this, { faceCount: m.faces, vertexCount: m.vertices, decodedFaces: m.decodedFaces,
        splitsApplied: m.splitsApplied, status: m.status });
      this._error = m.error;
      this._info = m.info;
    }
    this._pending.splice(0, taken);
    const changed = updates.length > 0 && this._mirror.apply(updates, this._info);
    this.complete = !!this._done && this._done.status === 'ok' && this.status === 'ok' &&
      this._pending.length === 0 &&
      (this.faceTarget !== null || this.splitsApplied === this._info.totalSplits);
    // The worker's 'done' comes once decoding ended (failed: with what arrived before the
    // damage applied), after the updates it posted.
    this.ended = this.complete || (!!this._done && this._done.status !== 'ok' && this._pending.length === 0);
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

// A texture reference (a file name or URI as the file states it, OBJ's backslashes too)
// resolved against the stream's URL.
function textureUrl(uri, base) {
  const u = uri.replace(/\\/g, '/');
  try {
    return base ? new URL(u, base).href : u;
  } catch (e) {
    return u;
  }
}

// How textures are sampled. The stream carries no sampler (a material is its name, base colour
// and texture references), so the default of glTF's sampler and of MTL (no -clamp) is taken,
// as pmz-view samples: repeated in u and v (texture coordinates outside [0, 1] tile), linear
// magnification, mipmapped linear minification.
export const PMZ_TEXTURE_SAMPLER = Object.freeze({ wrapS: RepeatWrapping, wrapT: RepeatWrapping,
  magFilter: LinearFilter, minFilter: LinearMipmapLinearFilter });

// One white texel: a material's map until its texture arrives, so the base colour is drawn
// meanwhile (as pmz-view does; a map without its image samples black) by the textured program
// itself (no recompile when the texture comes).
function whiteTexel() {
  const t = new DataTexture(new Uint8Array([255, 255, 255, 255]), 1, 1);
  t.colorSpace = SRGBColorSpace;
  t.needsUpdate = true;
  return t;
}

// three.js materials for a stream, indexed like its material table (the geometry's groups'
// materialIndex), one plain material without a table: MeshStandardMaterial with the base
// colour, the base colour texture (resolved relative to the .pmz URL, options.baseUrl or the
// stream's; sampled as PMZ_TEXTURE_SAMPLER says), vertex colours when the geometry has them,
// and smooth shading with decoded normals (flat without). Until a texture arrives, or when it
// cannot be loaded, the material's map is one white texel (the base colour is drawn); the
// texture becomes the map when it loads. Call once the base mesh is in (the geometry has its
// attributes). options: parameters (more MeshStandardMaterial parameters), color (without a
// table), textureLoader, sampler (PMZ_TEXTURE_SAMPLER's fields to override),
// onTextureLoad(texture, material) (e.g. to redraw, or to give the texture to the material's
// clones), onTextureError(url, error).
export function pmzMaterials(stream, options = {}) {
  const g = stream.geometry;
  const has = (name) => !!g.getAttribute(name);
  const base = options.baseUrl ?? stream.url ?? (typeof location === 'object' ? location.href : undefined);
  const loader = options.textureLoader ?? new TextureLoader();
  const make = (params) => new MeshStandardMaterial({ side: DoubleSide, roughness: 0.7,
    flatShading: !has('normal'), vertexColors: has('color'), ...options.parameters, ...params });
  const table = stream.materials();
  if (!table.length) return [make({ color: has('color') ? 0xffffff : options.color ?? 0xd8c8a8 })];
  const sampler = { ...PMZ_TEXTURE_SAMPLER, ...options.sampler };
  let white = null;
  return table.map((m) => {
    const material = make({ name: m.name, color: new Color(m.baseColor[0], m.baseColor[1], m.baseColor[2]),
      opacity: m.baseColor[3], transparent: m.baseColor[3] < 1 });
    if (m.baseColorTexture && has('uv')) {
      const url = textureUrl(m.baseColorTexture, base);
      material.map = white ??= whiteTexel();
      const texture = loader.load(url, (t) => {
        material.map = t;
        if (options.onTextureLoad) options.onTextureLoad(t, material);
      }, undefined,
      (e) => (options.onTextureError ? options.onTextureError(url, e) : console.warn(`pmz: texture ${url} not loaded`)));
      Object.assign(texture, sampler);
      texture.colorSpace = SRGBColorSpace;
    }
    return material;
  });
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

  // options.view: a PMZViewStream for the URL (on this thread). Updated each animation frame
  // (autoUpdate) until its base mesh is in; from then on the caller's update(camera) drives it.
  async _viewStream(source, onUpdate, auto) {
    const opts = this.options;
    let url = String(source);
    try {
      url = new URL(source, typeof location === 'object' ? location.href : undefined).href;
    } catch (e) { /* a relative URL without a page (node) */ }
    // (opts.maxFaces is the decoder's limit, createDecoder()'s: the view's budget is view.maxFaces.)
    const view = typeof opts.view === 'object' ? opts.view : {};
    const s = new PMZViewStream(await createDecoder(opts), url, { ...opts, ...view, maxFaces: view.maxFaces ?? 0,
      init: { headers: this.requestHeader, credentials: this.withCredentials ? 'include' : 'same-origin' } });
    s.source.onData = () => onUpdate && onUpdate(s);
    const tick = () => {
      s.update();
      if (onUpdate) onUpdate(s);
      if (!s.ended && !s.info().baseDone) requestAnimationFrame(tick);
    };
    if (auto) requestAnimationFrame(tick);
    return s;
  }

  async stream(source, onUpdate) {
    const opts = this.options;
    const auto = opts.autoUpdate !== false && typeof requestAnimationFrame === 'function';
    const isUrl = typeof source === 'string' || source instanceof URL;
    if (opts.view && isUrl) return this._viewStream(source, onUpdate, auto);
    const inWorker = opts.worker && typeof Worker === 'function';
    const s = inWorker ? new PMZWorkerStream(opts) : new PMZStream(await createDecoder(opts), opts);
    // Texture references resolve against it (pmzMaterials()).
    if (typeof source === 'string' || source instanceof URL) {
      try {
        s.url = new URL(source, typeof location === 'object' ? location.href : undefined).href;
      } catch (e) {  // a relative URL without a page (node)
        s.url = String(source);
      }
    }
    const tick = () => {
      s.update();
      if (onUpdate) onUpdate(s);
      if (!s.complete && !s.ended) requestAnimationFrame(tick);
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

// GLTFLoader plugin for PMZ_progressive_mesh (docs/gltf-binding.md, draft):
//   loader.register((parser) => new PMZGLTFPlugin(parser, options));
// GLTFLoader builds each primitive's base mesh as usual; once the scene is built, the stream in the
// extension's buffer view goes through PMZLoader.stream() (options: PMZLoader's, worker included)
// and the base's three.js meshes take the stream's geometry, which refines in place. One stream and
// decoder per glTF mesh that carries the extension (a scene GLB has several), shared by the nodes
// that use it; primitives without it are left alone. Works alike for load by URL and parse of an
// ArrayBuffer. With several materials the mesh's primitives (one per material) become one three.js
// mesh whose material array follows the stream's material table (glTF material k is the stream's
// material k). Each mesh's userData.pmzStream is its stream; the plugin's `streams` (the loaded
// glTF's userData.pmzStreams) lists them all (GLTFLoader's onLoad comes once they exist), and
// `ready` (userData.pmzReady) resolves once each shows its base or has failed (a stream the decoder
// refuses leaves the glTF base in place).
export class PMZGLTFPlugin {
  constructor(parser, options = {}) {
    this.name = 'PMZ_progressive_mesh';
    this.parser = parser;
    this.options = options;
    this.streams = [];
    this.ready = Promise.resolve([]);
  }

  afterRoot(result) {
    const parser = this.parser, json = parser.json;
    if (!(json.extensionsUsed || []).includes(this.name)) return null;
    // The primitives' three.js meshes, by glTF mesh and by parent (one instance of the mesh).
    const meshes = new Map();
    for (const scene of result.scenes) {
      scene.traverse((object) => {
        const a = object.isMesh ? parser.associations.get(object) : null;
        if (!a || a.meshes === undefined || a.primitives === undefined) return;
        const ext = json.meshes[a.meshes].primitives[a.primitives].extensions?.[this.name];
        if (!ext) return;  // (a version the decoder does not read fails it: the base stays)
        if (!meshes.has(a.meshes)) meshes.set(a.meshes, { ext, instances: new Map() });
        const instances = meshes.get(a.meshes).instances;
        const key = object.parent && object.parent.isGroup &&
          parser.associations.get(object.parent)?.meshes === a.meshes ? object.parent : object;
        if (!instances.has(key)) instances.set(key, []);
        instances.get(key).push({ object, primitive: a.primitives });
      });
    }
    const loader = new PMZLoader(undefined, { ...this.options, flipV: true });
    const started = [...meshes].map(async ([meshIndex, { ext, instances }]) => {
      const view = await parser.getDependency('bufferView', ext.bufferView);
      // Every glTF material: the stream's table (a material may have no base faces, so no
      // primitive of its own).
      const materials = await Promise.all((json.materials || []).map((_, k) => parser.getDependency('material', k)));
      let shown = false, resolveShown;
      const baseShown = new Promise((resolve) => { resolveShown = resolve; });
      const stream = await loader.stream(new Blob([view]), (s) => {
        if (shown || !s.geometry.getIndex()) return;
        shown = true;
        for (const parts of instances.values()) this._attach(s, meshIndex, parts, materials);
        resolveShown(s);
      });
      const settle = () => resolveShown(stream);
      stream.done.then(settle, settle);
      this.streams.push(stream);
      return { baseShown };  // (not the promise itself: onLoad waits for the streams only)
    });
    this.ready = Promise.all(started).then((all) => Promise.all(all.map((x) => x.baseShown)));
    Object.assign(result.userData, { pmzStreams: this.streams, pmzReady: this.ready });
    return Promise.all(started);
  }

  // One instance of the mesh: its first primitive's three.js mesh takes the stream's geometry
  // (with several materials: one per glTF material, the primitives' own where they have one,
  // as GLTFLoader adapted them, else GLTFLoader's material adapted the same way: vertex colours,
  // flat shading without normals); the other primitives' meshes leave the scene.
  _attach(stream, meshIndex, parts, materials) {
    const prims = this.parser.json.meshes[meshIndex].primitives;
    parts.sort((a, b) => a.primitive - b.primitive);
    const [first, ...rest] = parts;
    if (stream.materials().length > 1) {
      const g = stream.geometry;
      const own = new Map(parts.map((p) => [prims[p.primitive].material, p.object.material]));
      first.object.material = materials.map((m, k) => {
        if (own.has(k)) return own.get(k);
        const colors = !!g.getAttribute('color'), flat = !g.getAttribute('normal');
        if (!colors && !flat) return m;
        const copy = m.clone();
        if (colors) copy.vertexColors = true;
        if (flat) copy.flatShading = true;
        return copy;
      });
    }
    first.object.geometry = stream.geometry;
    first.object.userData.pmzStream = stream;
    for (const p of rest) p.object.removeFromParent();
  }
}
