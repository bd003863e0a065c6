// Streaming in headless Chromium over a throttled link: the viewer (web/dist/viewer) loads
// MESH.pmz from a node HTTP server on 127.0.0.1 paced to RATE bytes/s. From the page's own
// requestAnimationFrame timestamps: the first frame drawn with the object after the first body
// bytes arrived, and the gaps between frames until the stream is complete; from the Long Tasks
// API the page's main-thread tasks over 50 ms in that time (what blocks the page itself, apart
// from frames waiting on SwiftShader's rendering in the GPU process); and for comparison the
// median gap over 3 s of the finished mesh while nothing changes. The viewer draws only when
// something changed: gap_* are the page's frames (requestAnimationFrame, drawn or not: how
// responsive the page stays), redraw_gap_* the intervals between frames that drew the object,
// worst_gaps the three longest gaps with what the frame before each did (js: its whole
// requestAnimationFrame callback; a gap far longer than that is the frame's commit waiting for
// SwiftShader, see trace_chromium.mjs's long_tasks, or no core for the page). The viewer's draw
// budget (?drawms=0 turns it off) shows at most shown_max_while_decoding faces until decoding
// ends; final_frame_gap_ms is the frame after the finest level was shown (drawing the full
// mesh, after decoding: not among the gaps while decoding). first_object_faces: the faces of
// the first object frame (the base mesh; bunny00's has 4), first_1000_faces_ms the first
// frame with at least 1,000.
//
//   node web/bench/stream_chromium.mjs MESH.pmz [RATE=2000000] [RUNS=3] [WIDTHxHEIGHT=640x480]
//                                     [WORKER=1]   (0: decode on the page's thread)
//                                     [QUERY]      (more viewer parameters, e.g. drawms=0;
//                                                   'A|B': runs alternate A, B, A, B, ...)
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
  const s = await page.evaluate(() => ({ status: window.pmzStatus, timing: window.pmzTiming,
    frames: window.pmzFrames, longTasks: window.pmzLongTasks, calibration: window.pmzDrawCalibration || null }));
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
  // PMZ_BENCH_FRAMES=PREFIX: each run's frames and timings as PREFIX-RUN.json.
  if (process.env.PMZ_BENCH_FRAMES)
    writeFileSync(`${process.env.PMZ_BENCH_FRAMES}-${r}.json`, JSON.stringify(s));
  const { firstBytes, firstObjectFrame } = s.timing;
  const done = s.frames.find((f) => f.faces === s.status.faces && f.bytes === s.status.totalBytes);
  const during = s.frames.filter((f) => f.t >= firstBytes && (!done || f.t <= done.t));
  const gaps = during.slice(1).map((f, i) => f.t - during[i].t).sort((a, b) => a - b);
  const q = (p) => gaps.length ? +gaps[Math.min(gaps.length - 1, Math.floor(p * gaps.length))].toFixed(1) : null;
  // Frames that drew (the viewer redraws only on changes): the redraw interval while decoding.
  const drawn = during.filter((f) => f.drawn !== false);
  const redraws = drawn.slice(1).map((f, i) => f.t - drawn[i].t).sort((a, b) => a - b);
  // The three longest gaps, with the frame that ended each (what it did).
  const worst = during.slice(1).map((f, i) => ({ gap: +(f.t - during[i].t).toFixed(1), at: +(f.t - firstBytes).toFixed(1),
    faces: during[i].faces, work: +during[i].work.toFixed(1), render: +during[i].render.toFixed(1),
    js: +(during[i].js || 0).toFixed(1), drawn: during[i].drawn }))
    .sort((a, b) => b.gap - a.gap).slice(0, 3);
  const still = done ? s.frames.filter((f) => f.t > done.t + 500) : [];
  const stillGaps = still.slice(1).map((f, i) => f.t - still[i].t).sort((a, b) => a - b);
  // The frame after the one that showed the finest level: what drawing the full mesh cost
  // once decoding ended (not a gap while decoding).
  const doneAt = done ? s.frames.indexOf(done) : -1;
  const finalGap = doneAt >= 0 && doneAt + 1 < s.frames.length ? s.frames[doneAt + 1].t - done.t : null;
  const before = done ? during.filter((f) => f !== done) : during;
  results.push({ query, loadavg: +loadavg()[0].toFixed(1), faces: s.status.faces, error: s.status.error,
    first_object_ms: +(firstObjectFrame - firstBytes).toFixed(1), first_object_faces: s.timing.firstObjectFaces,
    // The base mesh can be a handful of faces: when a frame first drew 1,000 or more.
    first_1000_faces_ms: (() => {
      const f = s.frames.find((x) => x.drawn && x.faces >= 1000 && x.t >= firstBytes);
      return f ? +(f.t + f.work + f.render - firstBytes).toFixed(1) : null;
    })(),
    shown_max_while_decoding: Math.max(0, ...before.map((f) => f.faces)),
    final_frame_gap_ms: finalGap === null ? null : +finalGap.toFixed(1),
    calibration: s.calibration && { faces: s.calibration.faces, ms: +s.calibration.ms.toFixed(1) },
    complete_ms: done ? +(done.t - firstBytes).toFixed(1) : null, frames: during.length,
    gap_median_ms: q(0.5), gap_p95_ms: q(0.95), gap_max_ms: gaps.length ? +gaps[gaps.length - 1].toFixed(1) : null,
    gaps_over_50ms: gaps.filter((g) => g > 50).length,
    redraws: drawn.length, redraw_gap_median_ms: redraws.length ? +redraws[redraws.length >> 1].toFixed(1) : null,
    redraw_gap_max_ms: redraws.length ? +redraws[redraws.length - 1].toFixed(1) : null, worst_gaps: worst,
    static_gap_median_ms: stillGaps.length ? +stillGaps[stillGaps.length >> 1].toFixed(1) : null,
    // The page's own JS per frame: update() (applying the worker's ranges, or refining here)
    // and the render() call (queuing GL commands; SwiftShader draws in the GPU process).
    update_max_ms: +Math.max(0, ...during.map((f) => f.work)).toFixed(1),
    render_call_max_ms: +Math.max(0, ...during.map((f) => f.render)).toFixed(1),
    // The whole requestAnimationFrame callback (update, render() call, overlay), before the
    // frame that showed the finest level (its copy of the held-back mesh is after decoding).
    frame_js_max_ms: +Math.max(0, ...before.map((f) => f.js || 0)).toFixed(1),
    long_tasks: s.longTasks.filter((x) => x.start >= firstBytes && (!done || x.start <= done.t)).length,
    long_task_max_ms: +Math.max(0, ...s.longTasks.filter((x) => x.start >= firstBytes &&
      (!done || x.start <= done.t)).map((x) => x.duration)).toFixed(1) });
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
    'gap_max_ms', 'gaps_over_50ms', 'frames', 'redraw_gap_median_ms', 'shown_max_while_decoding', 'final_frame_gap_ms',
    'update_max_ms', 'frame_js_max_ms', 'long_task_max_ms']) out[k] = median(rs.map((x) => x[k]));
  return out;
});
console.log(JSON.stringify({ file: path.basename(file), viewer: path.resolve(viewerDir), rate, width, height, worker,
  loadavg: loadavg().map((x) => +x.toFixed(1)), medians, runs: results }, null, 1));
