// SPDX-License-Identifier: MIT
// pmz web viewer: streams a .pmz (?src=URL, the URL box, or a dropped file) into a three.js
// scene and refines it while the bytes arrive. This is the page's side: input (orbit, LOD
// slider, geomorphs, open), the overlay and the state for tests. The drawing side (render.js:
// scene, stream, frame loop, draw budget) runs in a Web Worker on the canvas transferred to it
// (OffscreenCanvas), where workers have WebGL2 and ?render=page is not given; else on this
// thread. Either way the two sides talk by the same messages.
import * as THREE from 'three';
import { OrbitControls } from './vendor/OrbitControls.js';

const params = new URLSearchParams(location.search);
const canvas = document.createElement('canvas');
document.body.prepend(canvas);
const overlay = document.getElementById('overlay');
const lod = document.getElementById('lod');
const morph = document.getElementById('morph');

// With software compositing (headless Chromium with SwiftShader) the thread that draws a WebGL
// canvas waits for every drawn frame to be read back: a worker keeps that wait off this thread
// (bunny00 at load 14-16, a frame every 33-117 ms drawn here, every 16.7 ms with the worker).
function workersDraw() {
  if (params.get('render') === 'page') return false;
  try {
    return typeof Worker === 'function' && typeof canvas.transferControlToOffscreen === 'function' &&
      typeof OffscreenCanvas === 'function' && !!new OffscreenCanvas(1, 1).getContext('webgl2');
  } catch (e) {
    return false;
  }
}

// The page's own camera for the orbit controls; each change goes to the drawing side.
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 100);
camera.position.set(0, 0, 3);
let controls = new OrbitControls(camera, canvas);

// State for tests and scripts: window.pmzStatus, timings (performance.now() ms of this page) and
// one entry per animation frame of this page (window.pmzFrames); the canvas's own frames come
// from window.pmzCanvasFrames().
const status = { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, ended: false, error: '' };
window.pmzStatus = status;
window.pmzTiming = { firstBytes: null, firstObjectFrame: null };
window.pmzFrames = [];
// Main-thread tasks over 50 ms (Long Tasks API, where supported): {start, duration}.
window.pmzLongTasks = [];
if (typeof PerformanceObserver === 'function' &&
    (PerformanceObserver.supportedEntryTypes || []).includes('longtask')) {
  new PerformanceObserver((list) => {
    for (const e of list.getEntries()) window.pmzLongTasks.push({ start: e.startTime, duration: e.duration });
  }).observe({ type: 'longtask' });
}
let info = null, overlayState = null;

// The drawing side: a worker, or render.js on this thread (then its clock is this one).
let send = null, clockOffset = 0;
const replies = new Map();
let nextCall = 0;
const queued = [];  // messages before the drawing side is ready
function post(message) {
  if (send) send(message); else queued.push(message);
}
function call(name, ...args) {
  const id = ++nextCall;
  return new Promise((resolve, reject) => {
    replies.set(id, { resolve, reject });
    post({ type: 'call', id, name, args });
  });
}
const onTime = (t) => (t === null || t === undefined ? t : t + clockOffset);
function receive(m) {
  if (m.type === 'state') {
    Object.assign(status, m.status);
    info = m.info;
    overlayState = m.overlay;
    window.pmzTiming = { firstBytes: onTime(m.timing.firstBytes), firstObjectFrame: onTime(m.timing.firstObjectFrame),
      firstObjectFaces: m.timing.firstObjectFaces };
    if (m.attributes) window.pmzAttributes = m.attributes;
    if (m.calibration) window.pmzDrawCalibration = m.calibration;
  } else if (m.type === 'fit') {
    camera.position.fromArray(m.position);
    controls.target.fromArray(m.target);
    controls.update();
    sendCamera();
  } else if (m.type === 'reply') {
    const r = replies.get(m.id);
    replies.delete(m.id);
    if (m.error !== undefined) r.reject(new Error(m.error)); else r.resolve(m.result);
  } else if (m.type === 'warn') {
    console.warn(m.text);
  }
}
function sendCamera() {
  post({ type: 'camera', position: camera.position.toArray(), quaternion: camera.quaternion.toArray() });
}
controls.addEventListener('change', sendCamera);

async function drawHere(target) {
  const { createView } = await import('./render.js');
  const view = createView({ canvas: target, width: window.innerWidth, height: window.innerHeight,
    pixelRatio: window.devicePixelRatio, query: location.search, post: receive });
  send = (message) => view.handle(message);
  window.pmzRenderer = 'page';
}
function start() {
  if (!workersDraw()) return drawHere(canvas);
  const worker = new Worker(new URL('./render_worker.js', import.meta.url), { type: 'module' });
  const offscreen = canvas.transferControlToOffscreen();
  // A worker that cannot draw after all (no WebGL2 there, or its module failed): a new canvas,
  // drawn here.
  const fallBack = () => {
    worker.terminate();
    const fresh = document.createElement('canvas');
    canvas.replaceWith(fresh);
    controls.dispose();
    controls = new OrbitControls(camera, fresh);
    controls.addEventListener('change', sendCamera);
    return drawHere(fresh).then(flush);
  };
  return new Promise((resolve) => {
    worker.onerror = () => fallBack().then(resolve);
    worker.onmessage = (e) => {
      const m = e.data;
      if (m.type === 'ready') {
        clockOffset = m.timeOrigin - performance.timeOrigin;
        worker.onmessage = (ev) => receive(ev.data);
        worker.onerror = (ev) => { status.error = `pmz viewer: drawing worker: ${ev.message}`; };
        send = (message) => worker.postMessage(message);
        window.pmzRenderer = 'worker';
        resolve();
      } else if (m.type === 'unavailable') {
        console.warn(`pmz viewer: drawing on the page (${m.error})`);
        fallBack().then(resolve);
      }
    };
    worker.postMessage({ type: 'init', canvas: offscreen, width: window.innerWidth, height: window.innerHeight,
      pixelRatio: window.devicePixelRatio, query: location.search }, [offscreen]);
  });
}
function flush() {
  for (const m of queued.splice(0)) send(m);
}
const ready = start().then(flush);

let faceTarget = null;  // null: follow the stream; else the LOD slider's face count
function setFaceTarget(faces) {
  faceTarget = faces;
  post({ type: 'faces', faces });
}
lod.addEventListener('input', () => {
  const v = Number(lod.value);
  const full = info && info.headerDone ? info.fullFaces : 0;
  setFaceTarget(v >= 1000 ? null : Math.max(1, Math.round(full * (v / 1000) ** 2)));
});

function open(source) {
  Object.assign(status, { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, ended: false, error: '' });
  window.pmzTiming = { firstBytes: null, firstObjectFrame: null };
  window.pmzFrames = [];
  window.pmzLongTasks = [];
  info = null;
  // Relative URLs resolve against this page, not the worker's script.
  post({ type: 'open', source: typeof source === 'string' ? new URL(source, location.href).href : source });
  post({ type: 'faces', faces: faceTarget });
}

// Each frame: the overlay, geomorphs on or off, and this page's frame record.
let morphSent = null;
function frame(t) {
  const tStart = performance.now();
  requestAnimationFrame(frame);
  if (morph.checked !== morphSent) {
    morphSent = morph.checked;
    post({ type: 'morph', on: morphSent });
  }
  const kb = (n) => (n / 1024).toFixed(1) + ' KiB';
  const o = overlayState;
  const text = o
    ? `faces     ${status.faces.toLocaleString()}` +
      (o.byView && status.maxFaces ? ` (budget ${status.maxFaces.toLocaleString()})` : '') +
      (o.limited ? ` shown (draw budget), ${o.decodedFaces.toLocaleString()} decoded` : '') +
      `\nvertices  ${status.vertices.toLocaleString()}\n` +
      `bytes     ${kb(status.bytes)} / ${status.totalBytes ? kb(status.totalBytes) : '?'}` +
      (o.byView ? ' fetched' : '') + '\n' +
      (o.byView && status.totalNodes ? `nodes     ${status.nodes} / ${status.totalNodes} resident\n`
        : `refine    ${o.rate.toLocaleString()} splits/s\n`) +
      (status.error ? `error     ${status.error}` : status.complete ? (o.byView ? 'view complete' : 'complete')
        : o.byView ? 'fetching for the view' : 'streaming')
    : status.error ? `error     ${status.error}` : overlay.textContent;
  if (text !== overlay.textContent) overlay.textContent = text;  // no layout for an unchanged text
  if (window.pmzFrames.length < 100000)
    window.pmzFrames.push({ t, faces: status.faces, bytes: status.bytes, js: performance.now() - tStart });
}
requestAnimationFrame(frame);

function resize() {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  post({ type: 'resize', width: window.innerWidth, height: window.innerHeight });
}
window.addEventListener('resize', resize);

// Tests and benchmarks (render.js's CALLS; each returns a promise): hold a face count (null
// follows the stream); the canvas's coverage and a downsampled copy; the same drawn from a
// geometry built afresh from the decoder's buffers; the geomorph check at time T; birth times;
// draw costs; the canvas's frames on this page's clock.
window.pmzSetFaces = (faces) => {
  setFaceTarget(faces);
  const full = info && info.headerDone ? info.fullFaces : 0;
  lod.value = faces === null ? 1000 : Math.min(999, Math.round(1000 * Math.sqrt(faces / Math.max(1, full))));
};
window.pmzSnapshot = () => call('snapshot');
window.pmzReferenceSnapshot = () => call('referenceSnapshot');
window.pmzGeomorphCheck = (T) => call('geomorphCheck', T);
window.pmzBirthTimes = () => call('birthTimes');
window.pmzDrawCost = (faceCounts, reps, morphing) => call('drawCost', faceCounts, reps, morphing);
window.pmzCanvasFrames = async () => (await call('frames')).map((f) => ({ ...f, t: f.t + clockOffset }));
window.pmzReady = ready;

if (params.get('src')) {
  document.getElementById('url').value = params.get('src');
  open(params.get('src'));
}
document.getElementById('open').onclick = () => open(document.getElementById('url').value);
document.getElementById('file').onchange = (e) => e.target.files[0] && open(e.target.files[0]);
const drop = document.getElementById('drop');
window.addEventListener('dragover', (e) => { e.preventDefault(); drop.style.display = 'flex'; });
window.addEventListener('dragleave', () => { drop.style.display = 'none'; });
window.addEventListener('drop', (e) => {
  e.preventDefault();
  drop.style.display = 'none';
  if (e.dataTransfer.files[0]) open(e.dataTransfer.files[0]);
});
