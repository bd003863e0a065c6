// SPDX-License-Identifier: MIT
// ?mode=page: this page draws the grid every frame; worker: a worker draws it on the canvas
// transferred to it (OffscreenCanvas) while this page only updates a text overlay; none: nothing
// draws (the machine's own share of the page's frame gaps). ?faces=N, ?ms=run time; ?busy=0: no
// worker kept busy (by default one is, in 8 ms slices, as the decoding worker is). Records
// window.probe: the page's requestAnimationFrame times, the drawing worker's, long tasks.
import * as THREE from 'three';
import { makeScene } from './scene.js';

const params = new URLSearchParams(location.search);
const mode = params.get('mode') || 'worker', faces = Number(params.get('faces') || 20000);
const ms = Number(params.get('ms') || 4000);
const canvas = document.getElementById('canvas'), overlay = document.getElementById('overlay');
const width = window.innerWidth, height = window.innerHeight;
window.probe = { done: false, page: [], worker: [], longTasks: [] };
new PerformanceObserver((list) => {
  for (const e of list.getEntries()) window.probe.longTasks.push({ start: e.startTime, duration: e.duration });
}).observe({ type: 'longtask' });
if (params.get('busy') !== '0') {
  const source = 'const c = new MessageChannel(); c.port1.onmessage = () => { const t = performance.now(); ' +
    'while (performance.now() - t < 8); c.port2.postMessage(0); }; c.port2.postMessage(0);';
  window.busyWorker = new Worker(URL.createObjectURL(new Blob([source], { type: 'text/javascript' })));
}
let draw = null;
if (mode === 'page') {
  draw = makeScene(THREE, canvas, width, height, faces);
} else if (mode === 'worker') {
  const offscreen = canvas.transferControlToOffscreen();
  const worker = new Worker(new URL('./render_worker.js', import.meta.url), { type: 'module' });
  worker.postMessage({ canvas: offscreen, width, height, faces, ms, timeOrigin: performance.timeOrigin }, [offscreen]);
  worker.onmessage = (e) => {
    window.probe.worker = e.data.frames;
    window.probe.error = e.data.error;
    window.probe.done = true;
  };
}
const start = performance.now();
function frame(t) {
  window.probe.page.push(t);
  if (draw) draw(t);
  overlay.textContent = `${mode} ${faces} faces, page frame ${window.probe.page.length}`;
  if (performance.now() - start < ms) requestAnimationFrame(frame);
  else if (mode !== 'worker') window.probe.done = true;
}
requestAnimationFrame(frame);
