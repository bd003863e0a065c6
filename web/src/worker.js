// pmz-decoder's Web Worker (module worker, started by PMZLoader with `worker: true`): fetches
// or receives the stream, feeds and refines the decoder here, off the page's thread, and posts
// what changed (copies of the new and rewritten ranges) after each time slice of refinement.
//
// Messages in:  {type: 'open', url, init?} | {type: 'open', blob} | {type: 'feed', bytes} |
//               {type: 'finish'} | {type: 'target', faces} (null: follow the stream) |
//               {type: 'snapshot', id} | {type: 'close'}
// Messages out: {type: 'update', ...} (see post()), {type: 'done', status, error},
//               {type: 'snapshot', id, positions, indices}, {type: 'failed', error}
import { createDecoder } from './index.js';

const SLICE_MS = 8;  // refinement between two updates (and between two reads of the network)

let decoder = null;
let options = {};
let faceTarget = null;
let bytes = 0, totalBytes = 0;
let firstBytesAt = null;  // ms since the epoch (timeOrigin + now: comparable across threads)
let finished = false, doneSent = false;
let shownVertices = 0;
let basePosted = false;
let scheduled = false;
let queue = [];  // messages that arrived before the decoder was created

// An immediate macrotask (no timer clamping), so network reads interleave with refinement.
const channel = new MessageChannel();
channel.port1.onmessage = () => { scheduled = false; work(); };
function schedule() {
  if (!scheduled) { scheduled = true; channel.port2.postMessage(0); }
}

function finish() {
  const status = decoder.status === 'ok' ? decoder.finish() : decoder.status;
  finished = true;
  schedule();
  return status;
}

async function pump(body) {
  const reader = body.getReader();
  for (;;) {
    const { done, value } = await reader.read();
    if (!decoder) return;  // closed meanwhile
    if (done) break;
    if (firstBytesAt === null) firstBytesAt = performance.timeOrigin + performance.now();
    bytes += value.length;
    if (decoder.feed(value) !== 'ok') break;
    schedule();
  }
  finish();
}

async function open(msg) {
  if (msg.url) {
    const r = await fetch(msg.url, msg.init);
    if (!r.ok) throw new Error(`pmz: ${msg.url}: HTTP ${r.status}`);
    totalBytes = Number(r.headers.get('content-length')) || 0;
    await pump(r.body);
  } else if (msg.blob) {
    totalBytes = msg.blob.size;
    await pump(msg.blob.stream());
  }
}

// Moves the level toward the target for one slice and posts the changes.
function work() {
  if (!decoder) return;
  const d = decoder;
  const info = d.info();
  if (info.baseDone && !basePosted) {  // the base mesh goes out before any refinement
    basePosted = true;
    post(info);
    schedule();
    return;
  }
  if (info.baseDone) {
    if (faceTarget === null) d.refineFor(SLICE_MS);
    else if (faceTarget !== d.faceCount) d.setFaceTarget(faceTarget);
  }
  post(info);
  if (d.status === 'ok' && faceTarget === null && d.splitsApplied < d.splitsAvailable) schedule();
  if (finished && !doneSent && (d.status !== 'ok' || faceTarget !== null ||
                                d.splitsApplied === info.totalSplits)) {
    doneSent = true;
    self.postMessage({ type: 'done', status: d.status, error: d.error });
  }
}

// The state and the changed ranges since the last post: positions [vertexBegin, vertices),
// indices [faceBegin, faces), rewritten faces below faceBegin as (face, a, b, c), and for
// geomorphs each new vertex's parent position (its own for base vertices and full uploads).
function post(info) {
  const d = decoder;
  const nv = d.vertexCount, nf = d.faceCount;
  const c = d.changes();
  const all = c.all;
  const vb = all ? 0 : Math.min(c.vertexBegin, nv), fb = all ? 0 : Math.min(c.faceBegin, nf);
  const msg = {
    type: 'update', vertices: nv, faces: nf, bytes, totalBytes, status: d.status,
    error: d.status === 'ok' ? '' : d.error, splitsApplied: d.splitsApplied, info, all, firstBytesAt,
    vertexBegin: vb, faceBegin: fb, positions: null, indices: null, modified: null, morph: null,
  };
  const transfer = [];
  if (info.baseDone) {
    const p = d.positions();
    msg.positions = p.slice(3 * vb, 3 * nv);
    msg.indices = d.indices().slice(3 * fb, 3 * nf);
    if (!all && c.modifiedFaces.length) {
      const t = d.indices(), faces = c.modifiedFaces, m = new Uint32Array(4 * faces.length);
      for (let i = 0; i < faces.length; ++i) {
        const f = faces[i];
        m[4 * i] = f;
        m[4 * i + 1] = t[3 * f];
        m[4 * i + 2] = t[3 * f + 1];
        m[4 * i + 3] = t[3 * f + 2];
      }
      msg.modified = m;
      transfer.push(m.buffer);
    }
    if (options.geomorph) {
      const from = all ? 0 : Math.max(vb, Math.min(shownVertices, nv));
      const parents = d.splitParents(), morph = new Float32Array(3 * (nv - from));
      for (let v = from, i = 0; v < nv; ++v, i += 3) {
        const u = parents[v], src = 3 * (u === 0xffffffff || all ? v : u);
        morph[i] = p[src];
        morph[i + 1] = p[src + 1];
        morph[i + 2] = p[src + 2];
      }
      msg.morph = morph;
      msg.morphBegin = from;
      transfer.push(morph.buffer);
    }
    transfer.push(msg.positions.buffer, msg.indices.buffer);
    shownVertices = nv;
    d.clearChanges();
  }
  self.postMessage(msg, transfer);
}

async function handle(msg) {
  switch (msg.type) {
    case 'open': await open(msg); break;
    case 'feed':
      if (firstBytesAt === null) firstBytesAt = performance.timeOrigin + performance.now();
      bytes += msg.bytes.length;
      if (decoder.status === 'ok') decoder.feed(msg.bytes);
      schedule();
      break;
    case 'finish': finish(); break;
    case 'target': faceTarget = msg.faces; schedule(); break;
    case 'snapshot':
      self.postMessage({ type: 'snapshot', id: msg.id, positions: decoder.positions().slice(),
        indices: decoder.indices().slice() });
      break;
    case 'close': decoder.dispose(); decoder = null; self.close(); break;
  }
}

function fail(e) {
  self.postMessage({ type: 'failed', error: String(e && e.message ? e.message : e).split('\n')[0] });
}

self.onmessage = (e) => {
  const msg = e.data;
  if (msg.type === 'init') {
    options = msg.options || {};
    totalBytes = msg.totalBytes || 0;
    createDecoder(options).then((d) => {
      decoder = d;
      for (const m of queue) handle(m).catch(fail);
      queue = null;
    }, fail);
  } else if (queue) {
    queue.push(msg);
  } else {
    handle(msg).catch(fail);
  }
};
