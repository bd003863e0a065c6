// SPDX-License-Identifier: MIT
// Streaming in headless Chromium over a throttled link: the viewer (web/dist/viewer) loads
// MESH.pmz from a node HTTP server on 127.0.0.1 paced to RATE bytes/s. Two kinds of frames:
// the page's (its main thread's requestAnimationFrame: how responsive the page stays, input and
// overlay; window.pmzFrames) and the canvas's (the drawing side's frame loop, in the drawing
// worker by default, on the page with render=page; window.pmzCanvasFrames()). gap_* are the
// page's frames between the first body bytes and the frame that showed the finest level (the
// target "the page keeps a frame at least every 50 ms while decoding"); redraw_gap_* the
// intervals between the canvas's frames that drew (new geometry, view or glide), new_level_gap_*
// between those that drew a new face count; worst_gaps the three longest page gaps (js: that
// page frame's callback), worst_redraw_gaps the three longest redraw intervals with what the
// drawing frame before each did (work: update(), render: the render() call, js: its whole
// callback; a gap far longer is the frame waiting for SwiftShader's read-back, see
// trace_chromium.mjs, or no core). From the Long Tasks API the page's main-thread tasks over
// 50 ms in that time. The viewer's draw budget (?drawms=0 turns it off) shows at most
// shown_max_while_decoding faces until decoding ends; final_frame_gap_ms is the canvas frame
// after the finest level was shown (drawing the full mesh, after decoding). first_object_faces:
// the faces of the first object frame (the base mesh; bunny00's has 4), first_1000_faces_ms
// the first drawn frame with at least 1,000; static_gap_median_ms the canvas's frames over 3 s
// of the finished mesh while nothing changes.
//
//   node web/bench/stream_chromium.mjs MESH.pmz [RATE=2000000] [RUNS=3] [WIDTHxHEIGHT=640x480]
//                                     [WORKER=1]   (0: decode on the drawing thread)
//                                     [QUERY]      (more viewer parameters, e.g. render=page,
//                                                   drawms=0; 'A|B': runs alternate A, B, ...)
// With gputime=1 in QUERY, each drawn canvas frame's time in the GPU process (render.js) gives
// gpu_median_ms / gpu_max_ms while decoding and, in worst_gaps, gpu: the longest of the canvas
// frames drawn in the 100 ms before that page gap ended.
// PMZ_VIEWER_DIR: another built viewer; PMZ_BENCH_FRAMES=PREFIX: raw frames per run.
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { loadavg, tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

import { CHROMIUM_ARGS, serveViewer } from '../test/serve.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [file, rateArg, runsArg, sizeArg, workerArg, extraQuery] = process.argv.slice(2);
const worker = workerArg !== '0';
const rate = Number(rateArg || 2e6), runs = Number(runsArg || 3);
const [width, height] = (sizeArg || '640x480').split('x').map(Number);
const viewerDir = process.env.PMZ_VIEWER_DIR || path.join(here, '..', 'dist', 'viewer');
const server = await serveViewer(path.resolve(viewerDir), { 'mesh.pmz': path.resolve(file) }, rate);
const STATIC_MS = 3000;  // frames of the finished mesh, for static_gap_median_ms
const results = [];
const variants = (extraQuery || '').split('|');
for (let r = 0; r < runs * variants.length; ++r) {
  const query = variants[r % variants.length];
  const profile = mkdtempSync(path.join(tmpdir(), 'pmz-bench-chromium-'));
  const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true, protocolTimeout: 900000,
    args: [...CHROMIUM_ARGS, `--user-data-dir=${profile}`] });
  const page = await browser.newPage();
  await page.setViewport({ width, height });
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?src=/stream/mesh.pmz${worker ? '' : '&worker=0'}` +
    (query ? `&${query}` : ''));
  await page.waitForFunction(() => window.pmzStatus.complete || window.pmzStatus.error,
    { timeout: 600000, polling: 200 });
  // The same full mesh drawn while nothing changes: what rendering alone costs per frame.
  await new Promise((r) => setTimeout(r, STATIC_MS + 500));
  const s = await page.evaluate(async () => ({ status: window.pmzStatus, timing: window.pmzTiming,
    frames: window.pmzFrames, canvasFrames: await window.pmzCanvasFrames(), longTasks: window.pmzLongTasks,
    calibration: window.pmzDrawCalibration || null, renderer: window.pmzRenderer }));
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
  // PMZ_BENCH_FRAMES=PREFIX: each run's frames and timings as PREFIX-RUN.json.
  if (process.env.PMZ_BENCH_FRAMES)
    writeFileSync(`${process.env.PMZ_BENCH_FRAMES}-${r}.json`, JSON.stringify(s));
  const { firstBytes, firstObjectFrame } = s.timing;
  const cf = s.canvasFrames;
  // The canvas frame that showed the finest level: the end of decoding.
  const done = cf.find((f) => f.drawn && f.faces === s.status.faces && f.bytes === s.status.totalBytes);
  const inWindow = (f) => f.t >= firstBytes && (!done || f.t <= done.t);
  const intervals = (frames) => frames.slice(1).map((f, i) => f.t - frames[i].t).sort((a, b) => a - b);
  const quantile = (xs, p) => xs.length ? +xs[Math.min(xs.length - 1, Math.floor(p * xs.length))].toFixed(1) : null;
  const top = (xs) => xs.length ? +xs[xs.length - 1].toFixed(1) : null;
  // The page's frames while decoding.
  const during = s.frames.filter(inWindow);
  const gaps = intervals(during);
  // The canvas's frames that drew, and those that drew a new face count.
  const canvasDuring = cf.filter(inWindow);
  const drawn = canvasDuring.filter((f) => f.drawn);
  const redraws = intervals(drawn);
  const levels = drawn.filter((f, i) => i === 0 || f.faces !== drawn[i - 1].faces);
  const newLevels = intervals(levels);
  // gpu: the longest time a canvas frame drawn within the 100 ms before the gap's end took in
  // the GPU process (its fence, see render.js), when recorded.
  const gpuBefore = (t) => Math.max(0, ...cf.filter((c) => c.drawn && c.gpu !== undefined && c.t <= t && c.t > t - 100)
    .map((c) => c.gpu));
  const worst = during.slice(1).map((f, i) => ({ gap: +(f.t - during[i].t).toFixed(1), at: +(f.t - firstBytes).toFixed(1),
    faces: during[i].faces, js: +(during[i].js || 0).toFixed(1), gpu: +gpuBefore(f.t).toFixed(1) }))
    .sort((a, b) => b.gap - a.gap).slice(0, 3);
  const worstRedraws = drawn.slice(1).map((f, i) => ({ gap: +(f.t - drawn[i].t).toFixed(1), at: +(f.t - firstBytes).toFixed(1),
    faces: drawn[i].faces, work: +drawn[i].work.toFixed(1), render: +drawn[i].render.toFixed(1),
    js: +(drawn[i].js || 0).toFixed(1) })).sort((a, b) => b.gap - a.gap).slice(0, 3);
  const still = done ? cf.filter((f) => f.t > done.t + 500) : [];
  const stillGaps = intervals(still);
  // The canvas frame after the one that showed the finest level: what drawing the full mesh
  // cost once decoding ended (not a gap while decoding).
  const doneAt = done ? cf.indexOf(done) : -1;
  const finalGap = doneAt >= 0 && doneAt + 1 < cf.length ? cf[doneAt + 1].t - done.t : null;
  const before = done ? canvasDuring.filter((f) => f !== done) : canvasDuring;
  const tasks = s.longTasks.filter((x) => x.start >= firstBytes && (!done || x.start <= done.t));
  results.push({ query, renderer: s.renderer, loadavg: +loadavg()[0].toFixed(1), faces: s.status.faces, error: s.status.error,
    first_object_ms: +(firstObjectFrame - firstBytes).toFixed(1), first_object_faces: s.timing.firstObjectFaces,
    // The base mesh can be a handful of faces: when a frame first drew 1,000 or more.
    first_1000_faces_ms: (() => {
      const f = cf.find((x) => x.drawn && x.faces >= 1000 && x.t >= firstBytes);
      return f ? +(f.t + f.work + f.render - firstBytes).toFixed(1) : null;
    })(),
    shown_max_while_decoding: Math.max(0, ...before.map((f) => f.faces)),
    final_frame_gap_ms: finalGap === null ? null : +finalGap.toFixed(1),
    calibration: s.calibration && { faces: s.calibration.faces, ms: +s.calibration.ms.toFixed(1) },
    complete_ms: done ? +(done.t - firstBytes).toFixed(1) : null, frames: during.length,
    gap_median_ms: quantile(gaps, 0.5), gap_p95_ms: quantile(gaps, 0.95), gap_max_ms: top(gaps),
    gaps_over_50ms: gaps.filter((g) => g > 50).length, worst_gaps: worst,
    redraws: drawn.length, redraw_gap_median_ms: quantile(redraws, 0.5), redraw_gap_p95_ms: quantile(redraws, 0.95),
    redraw_gap_max_ms: top(redraws), new_levels: levels.length, new_level_gap_median_ms: quantile(newLevels, 0.5),
    new_level_gap_max_ms: top(newLevels), worst_redraw_gaps: worstRedraws,
    static_gap_median_ms: stillGaps.length ? +stillGaps[stillGaps.length >> 1].toFixed(1) : null,
    // The drawing side's JS per frame: update() (applying the worker's ranges, or refining
    // there) and the render() call (queuing GL commands; SwiftShader draws in the GPU process).
    update_max_ms: +Math.max(0, ...canvasDuring.map((f) => f.work)).toFixed(1),
    render_call_max_ms: +Math.max(0, ...canvasDuring.map((f) => f.render)).toFixed(1),
    // Its whole frame callback, before the frame that showed the finest level (its copy of the
    // held-back mesh is after decoding); and the page's own frame callbacks.
    frame_js_max_ms: +Math.max(0, ...before.map((f) => f.js || 0)).toFixed(1),
    page_js_max_ms: +Math.max(0, ...during.map((f) => f.js || 0)).toFixed(1),
    long_tasks: tasks.length, long_task_max_ms: +Math.max(0, ...tasks.map((x) => x.duration)).toFixed(1),
    // The canvas frames' time in the GPU process while decoding (gputime=1, render.js).
    ...(() => {
      const g = before.filter((f) => f.drawn && f.gpu !== undefined).map((f) => f.gpu).sort((a, b) => a - b);
      return { gpu_median_ms: quantile(g, 0.5), gpu_max_ms: top(g) };
    })() });
}
server.close();
// Per query: the median of each figure over its runs (the lower one of an even count).
const median = (xs) => {
  const v = xs.filter((x) => typeof x === 'number').sort((a, b) => a - b);
  return v.length ? v[(v.length - 1) >> 1] : null;
};
const medians = variants.map((query) => {
  const rs = results.filter((x) => x.query === query), out = { query, runs: rs.length };
  for (const k of ['loadavg', 'first_object_ms', 'first_1000_faces_ms', 'complete_ms', 'gap_median_ms', 'gap_p95_ms',
    'gap_max_ms', 'gaps_over_50ms', 'frames', 'redraw_gap_median_ms', 'redraw_gap_p95_ms', 'redraw_gap_max_ms',
    'new_level_gap_median_ms', 'new_level_gap_max_ms', 'shown_max_while_decoding', 'final_frame_gap_ms',
    'update_max_ms', 'frame_js_max_ms', 'page_js_max_ms', 'long_tasks', 'long_task_max_ms', 'gpu_median_ms', 'gpu_max_ms']) out[k] = median(rs.map((x) => x[k]));
  return out;
});
console.log(JSON.stringify({ file: path.basename(file), viewer: path.resolve(viewerDir), rate, width, height, worker,
  loadavg: loadavg().map((x) => +x.toFixed(1)), medians, runs: results }, null, 1));
