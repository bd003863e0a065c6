// three.js loader for pmz: a BufferGeometry updated in place as the stream arrives and refines.
// Only the changed ranges are uploaded (BufferAttribute.addUpdateRange, three r159+).
import { Box3, BufferAttribute, BufferGeometry, Loader, Sphere, Vector3 } from 'three';
import { createDecoder, feedStream } from './index.js';

const RUNS_MAX = 64;  // more rewritten-face runs than this upload as one span

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
    const info = this.decoder.info();
    const g = this.geometry;
    const vcap = Math.max(vertices, Math.min(info.fullVertices, 1 << 24), 2 * this._vertexCap);
    const fcap = Math.max(faces, Math.min(info.fullFaces, 1 << 25), 2 * this._faceCap);
    const grow = (name, old, size, itemSize, Type) => {
      const a = new BufferAttribute(new Type(size * itemSize), itemSize);
      if (old) a.array.set(old.array.subarray(0, Math.min(old.array.length, a.array.length)));
      if (name) g.setAttribute(name, a);
      return a;
    };
    if (vertices > this._vertexCap) {
      grow('position', g.getAttribute('position'), vcap, 3, Float32Array);
      if (this.geomorph) grow('pmzMorph', g.getAttribute('pmzMorph'), vcap, 4, Float32Array);
      this._vertexCap = vcap;
    }
    if (faces > this._faceCap) {
      g.setIndex(grow(null, g.getIndex(), 3 * fcap, 1, Uint32Array));  // itemSize 1: three counts indices
      this._faceCap = fcap;
    }
    const box = new Box3(new Vector3(...info.bboxMin), new Vector3(...info.bboxMax));
    g.boundingBox = box;
    g.boundingSphere = box.getBoundingSphere(new Sphere());
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
      const faces = Uint32Array.from(c.modifiedFaces).sort();
      for (const f of faces) index.array.set(t.subarray(3 * f, 3 * f + 3), 3 * f);
      const runs = [];
      for (const f of faces) {
        const last = runs[runs.length - 1];
        if (last && f <= last[1]) last[1] = Math.max(last[1], f + 1);
        else runs.push([f, f + 1]);
      }
      if (runs.length > RUNS_MAX) runs.splice(0, runs.length, [runs[0][0], runs[runs.length - 1][1]]);
      for (const [a, b] of runs) index.addUpdateRange(3 * a, 3 * (b - a));
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
  return () => { uniforms.pmzTime.value = clock.now() / 1000; };
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
      if (!loaded && s.decoder.info().baseDone) {
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
    const s = new PMZStream(await createDecoder(opts), opts);
    const auto = opts.autoUpdate !== false && typeof requestAnimationFrame === 'function';
    const tick = () => {
      s.update();
      if (onUpdate) onUpdate(s);
      if (!s.complete && s.status === 'ok') requestAnimationFrame(tick);
    };
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
      return feedStream({ feed: (b) => s.feed(b), finish: () => s.finish() }, body,
                        () => onUpdate && onUpdate(s));
    })();
    return s;
  }
}
