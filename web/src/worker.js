// SPDX-License-Identifier: MIT
// pmz-decoder's Web Worker (module worker, started by PMZLoader with `worker: true`): fetches
// or receives the stream, feeds and refines the decoder here, off the page's thread, and posts
// what changed (copies of the new and rewritten ranges) after each time slice of refinement.
//
// Messages in:  {type: 'open', url, init?} | {type: 'open', blob} | {type: 'feed', bytes} |
//               {type: 'finish'} | {type: 'target', faces} (null: follow the stream) |
//               {type: 'limit', faces} (null: none; see PMZWorkerStream.faceLimit) |
//               {type: 'pause', ms} (no refinement for ms) |
//               {type: 'snapshot', id} | {type: 'close'}
// Messages out: {type: 'update', ...} (see post()), {type: 'done', status, error} (decoding
//               ended: see work()),
//               {type: 'snapshot', id, positions, indices, render}, {type: 'failed', error}
import { createDecoder } from './index.js';
import { renderArrays, renderUpdate, transferables } from './render_update.js';

const SLICE_MS = 8;  // refinement between two updates (and between two reads of the network)

let decoder = null;
let options = {};
let faceTarget = null;
// Following the stream, the page shows at most this many faces until decoding ends:
// refinement goes up to it; while bytes arrive it waits there, once every byte is in it goes
// on, with the ranges held back (the change report accumulates) until every split is applied.
let faceLimit = null;
let shown = { faces: 0, vertices: 0 };  // the level the page was last sent
let bytes = 0, totalBytes = 0;
let firstBytesAt = null;  // ms since the epoch (timeOrigin + now: comparable across threads)
let finished = false, doneSent = false;
// A failed stream (truncated or damaged) still shows what arrived before the damage, as
// pmz-decode --salvage does: refinement goes on while it applies splits; stalled once it
// applies none (every split that arrived is in, or the next one is the damaged one).
let stalled = false;
let renderState = { shownVertices: 0 };
let materialsPosted = false;
let basePosted = false;
let scheduled = false;
let pausedUntil = 0, pauseTimer = null;  // performance.now() ms; see 'pause'
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

// The splits to apply now, following the stream: within the face limit (a split adds at most
// two faces), past it only once every byte is in (then held back: see faceLimit).
function splitRoom(faces) {
  if (faceLimit === null) return Infinity;
  const within = Math.floor((faceLimit - faces) / 2);
  return within > 0 ? within : finished ? Infinity : 0;
}

// Moves the level toward the target for one slice and posts the changes (or, held back by
// the face limit, only the progress).
function work() {
  if (!decoder) return;
  const wait = pausedUntil - performance.now();
  if (wait > 0) {  // paused: the bytes still arrive (pump), refinement waits
    if (pauseTimer === null) pauseTimer = setTimeout(() => { pauseTimer = null; schedule(); }, wait);
    return;
  }
  const d = decoder;
  const info = d.info();
  if (info.baseDone && !basePosted) {  // the base mesh goes out before any refinement
    basePosted = true;
    post(info, true);
    schedule();
    return;
  }
  const room = () => splitRoom(d.faceCount);
  if (info.baseDone) {
    if (faceTarget === null) {
      if (room() > 0 && d.refineFor(SLICE_MS, room()) === 0 && d.status !== 'ok') stalled = true;
    } else if (faceTarget !== d.faceCount) {
      d.setFaceTarget(faceTarget);
    }
  }
  // Decoding ended: every byte in and every split applied, or failed with nothing more to apply.
  const failed = d.status !== 'ok';
  const decoded = finished && (d.splitsApplied === info.totalSplits ||
                               failed && (!info.baseDone || stalled || d.splitsApplied >= d.splitsAvailable));
  post(info, faceTarget !== null || faceLimit === null || d.faceCount <= faceLimit || decoded);
  if (!stalled && faceTarget === null && d.splitsApplied < d.splitsAvailable && room() > 0) schedule();
  if (finished && !doneSent && (decoded || faceTarget !== null)) {
    doneSent = true;
    self.postMessage({ type: 'done', status: d.status, error: d.error });
  }
}

// The state and, once the base mesh is in and `show`, the changed ranges since the last post
// (render_update.js: copies, transferred), with the material table in the first. Without
// `show` the counts are those of the level the page has.
function post(info, show) {
  const d = decoder;
  const send = show && info.baseDone;
  if (send) shown = { faces: d.faceCount, vertices: d.vertexCount };
  const msg = {
    type: 'update', vertices: shown.vertices, faces: shown.faces, decodedFaces: d.faceCount, bytes,
    totalBytes, status: d.status, error: d.status === 'ok' ? '' : d.error,
    splitsApplied: d.splitsApplied, info, firstBytesAt, render: null, materials: null,
  };
  let transfer = [];
  if (send) {
    if (!materialsPosted) {
      materialsPosted = true;
      msg.materials = d.materials();
    }
    msg.render = renderUpdate(d, renderState, { copy: true, geomorph: options.geomorph });
    transfer = transferables(msg.render);
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
      // The page stops feeding at an error: no more bytes (finish() keeps the error).
      if (decoder.status === 'ok' && decoder.feed(msg.bytes) !== 'ok') finish();
      schedule();
      break;
    case 'finish': finish(); break;
    case 'target': faceTarget = msg.faces; schedule(); break;
    case 'limit': faceLimit = msg.faces; schedule(); break;
    case 'pause': pausedUntil = performance.now() + msg.ms; break;
    case 'snapshot':
      self.postMessage({ type: 'snapshot', id: msg.id, positions: decoder.positions().slice(),
        indices: decoder.indices().slice(), render: renderArrays(decoder) });
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
    faceLimit = options.faceLimit ?? null;
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
