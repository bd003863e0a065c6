// SPDX-License-Identifier: MIT
// Where the time goes while the viewer streams a mesh in headless Chromium: one streaming run
// (as stream_chromium.mjs: MESH.pmz paced to RATE bytes/s from 127.0.0.1) under a Chromium
// trace, summed per process and thread (the page's main thread, its decoding worker, the GPU
// process's threads: SwiftShader draws there) and, per thread, the busiest top-level event
// names by self time. Times from the first body byte to the stream's completion.
// long_tasks: the page's main-thread tasks of at least 50 ms in that window (what the Long
// Tasks API reports), each split by what its time went to (wall, the nearest enclosing event
// of a kind): the animation frame's JS (the viewer's frame(): update() and the render()
// call), the canvas read-back in the frame's commit (GLES2::ReadPixels: with software
// compositing, as headless Chromium with SwiftShader has it, the page's thread reads each
// drawn WebGL frame back and waits until SwiftShader has drawn it), other waits for the GPU
// process (gpu_wait: e.g. in the frame's GL calls when the command or transfer buffer is full),
// the rest of the commit, style/layout/paint, the worker's messages (deserializing its
// updates), GC, and the rest. cpu_ms: the task's own CPU time (under load far below its wall).
//
//   node web/bench/trace_chromium.mjs MESH.pmz [RATE=2000000] [WIDTHxHEIGHT=640x480] [QUERY]
//                                    [TRACE_OUT.json]   (keeps the raw trace: chrome://tracing)
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { loadavg, tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

import { CHROMIUM_ARGS, serveViewer } from '../test/serve.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [file, rateArg, sizeArg, extraQuery, traceOut] = process.argv.slice(2);
const rate = Number(rateArg || 2e6);
const [width, height] = (sizeArg || '640x480').split('x').map(Number);
const viewerDir = process.env.PMZ_VIEWER_DIR || path.join(here, '..', 'dist', 'viewer');
const server = await serveViewer(path.resolve(viewerDir), { 'mesh.pmz': path.resolve(file) }, rate);
const profile = mkdtempSync(path.join(tmpdir(), 'pmz-bench-chromium-'));
const tracePath = traceOut || path.join(profile, 'trace.json');
const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
  protocolTimeout: 900000, args: [...CHROMIUM_ARGS, `--user-data-dir=${profile}`] });
let trace, state;
try {
  const page = await browser.newPage();
  await page.setViewport({ width, height });
  // The viewer waits for ?src until the trace runs: it opens the stream through its URL box.
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html` + (extraQuery ? `?${extraQuery}` : ''));
  await page.tracing.start({ path: tracePath, categories: ['devtools.timeline', 'toplevel', 'v8.execute', 'blink',
    'gpu', 'cc', 'viz', 'disabled-by-default-devtools.timeline', 'disabled-by-default-gpu.service', 'blink.user_timing'] });
  await page.evaluate(() => {
    document.getElementById('url').value = '/stream/mesh.pmz';
    document.getElementById('open').click();
  });
  await page.waitForFunction(() => window.pmzStatus.complete || window.pmzStatus.error,
    { timeout: 600000, polling: 200 });
  // A user-timing mark ties the page's clock to the trace's.
  state = await page.evaluate(() => {
    performance.mark('pmz-trace-clock');
    return { status: window.pmzStatus, timing: window.pmzTiming, now: performance.now(), frames: window.pmzFrames };
  });
  await page.tracing.stop();
  trace = JSON.parse(readFileSync(tracePath, 'utf8'));
} finally {
  await browser.close();
  server.close();
}
const events = trace.traceEvents || trace;
// Process and thread names.
const procName = new Map(), threadName = new Map();
for (const e of events) {
  if (e.ph !== 'M') continue;
  if (e.name === 'process_name') procName.set(e.pid, e.args.name);
  if (e.name === 'thread_name') threadName.set(`${e.pid}:${e.tid}`, e.args.name);
}
// The window, first body byte to completion, on the trace's clock (microseconds).
const done = state.frames.find((f) => f.faces === state.status.faces && f.bytes === state.status.totalBytes);
const mark = events.find((e) => e.name === 'pmz-trace-clock' && e.ts);
if (!mark || !done) throw new Error('no clock mark or no complete frame in the trace');
const tStart = mark.ts - (state.now - state.timing.firstBytes) * 1000;
const tStop = mark.ts - (state.now - done.t) * 1000;
const windowMs = (tStop - tStart) / 1000;
// Per thread, the self time of each complete event ('X': its duration minus its children's)
// within the window, wall clock and the thread's own CPU time (tdur) where the trace has it.
// Under load the two differ by the time the thread waited for a core.
const perThread = new Map();
const byThread = new Map();
for (const e of events) {
  if (e.ph !== 'X' || e.dur === undefined) continue;
  const key = `${e.pid}:${e.tid}`;
  if (!byThread.has(key)) byThread.set(key, []);
  byThread.get(key).push(e);
}
const clip = (start, dur) => Math.max(0, Math.min(start + dur, tStop) - Math.max(start, tStart));
for (const [key, list] of byThread) {
  list.sort((x, y) => x.ts - y.ts || y.dur - x.dur);
  const wall = new Map(), cpu = new Map(), stack = [];
  const bump = (m, name, v) => m.set(name, (m.get(name) || 0) + v);
  for (const e of list) {
    while (stack.length && stack[stack.length - 1].ts + stack[stack.length - 1].dur <= e.ts) stack.pop();
    const share = e.dur > 0 ? clip(e.ts, e.dur) / e.dur : 0;
    const parent = stack[stack.length - 1];
    if (parent) {
      bump(wall, parent.name, -clip(e.ts, Math.min(e.dur, parent.ts + parent.dur - e.ts)));
      bump(cpu, parent.name, -(e.tdur || 0) * share);
    }
    bump(wall, e.name, clip(e.ts, e.dur));
    bump(cpu, e.name, (e.tdur || 0) * share);
    stack.push(e);
  }
  const total = [...wall.values()].reduce((x, y) => x + y, 0);
  if (total > 0) perThread.set(key, { total, cpuTotal: [...cpu.values()].reduce((x, y) => x + y, 0), wall, cpu });
}
const ms = (us) => +(us / 1000).toFixed(1);
const threads = [...perThread.entries()].map(([key, t]) => {
  const pid = Number(key.split(':')[0]);
  return { process: procName.get(pid) || pid, thread: threadName.get(key) || key, busy_ms: ms(t.total),
    cpu_ms: ms(t.cpuTotal),
    top: [...t.wall.entries()].sort((a, b) => b[1] - a[1]).slice(0, 6)
      .map(([n, d]) => `${n}: ${ms(d)} ms wall, ${ms(t.cpu.get(n) || 0)} cpu`) };
}).filter((t) => t.busy_ms >= 5).sort((a, b) => b.busy_ms - a.busy_ms);
rmSync(profile, { recursive: true, force: true });

// The page's main thread: the one that ran the animation frames.
const frameCounts = new Map();
for (const e of events)
  if (e.name === 'FireAnimationFrame') frameCounts.set(`${e.pid}:${e.tid}`, (frameCounts.get(`${e.pid}:${e.tid}`) || 0) + 1);
const pageKey = [...frameCounts.entries()].sort((a, b) => b[1] - a[1])[0]?.[0];
const KINDS = [['frame_js', /^FireAnimationFrame$/], ['canvas_readback', /^GLES2::ReadPixels$/], ['commit_other', /^Commit$/],
  ['style_layout_paint', /^WebFrameWidgetImpl::UpdateLifecycle$/], ['worker_messages', /^HandlePostMessage$/],
  ['gc', /^(MinorGC|MajorGC|V8\.GC_SCAVENGER|V8\.GCFinalizeMC|BlinkGC\.|CppGC\.)/]];
const GPU_WAIT = /^(CommandBufferProxyImpl::WaitForGetOffset|ImplementationBase::WaitForCmd|CommandBufferHelper::Finish)$/;
const longTasks = [];
if (pageKey) {
  const list = byThread.get(pageKey) || [];  // sorted above
  const stack = [];
  let task = null;
  const close = () => {
    if (task && task.dur >= 50000 && task.ts >= tStart && task.ts <= tStop) longTasks.push(task);
  };
  for (const e of list) {
    while (stack.length && stack[stack.length - 1].ts + stack[stack.length - 1].dur <= e.ts) stack.pop();
    if (!stack.length) {
      close();
      task = { ts: e.ts, dur: e.dur, cpu: e.tdur || 0, self: new Map(), events: [] };
    }
    // This event's time leaves its parent's kind for its own (or the parent's, if none).
    const parent = stack[stack.length - 1];
    let kind = KINDS.find(([, re]) => re.test(e.name))?.[0] || (parent ? parent.kind : 'other');
    // Waiting for the GPU process elsewhere than in the read-back (in the frame's GL calls: a
    // full command buffer or transfer buffer waits for SwiftShader to catch up).
    if (GPU_WAIT.test(e.name) && kind !== 'canvas_readback') kind = 'gpu_wait';
    e.kind = kind;
    const bump = (k, v) => task.self.set(k, (task.self.get(k) || 0) + v);
    if (parent) bump(parent.kind, -Math.min(e.dur, parent.ts + parent.dur - e.ts));
    bump(kind, e.dur);
    stack.push(e);
  }
  close();
}
const long_tasks = longTasks.map((t) => ({ at_ms: +((t.ts - tStart) / 1000).toFixed(1), ms: ms(t.dur), cpu_ms: ms(t.cpu),
  parts: Object.fromEntries([...t.self.entries()].filter(([, v]) => v >= 500).sort((a, b) => b[1] - a[1])
    .map(([k, v]) => [k, ms(v)])) }));
const long_task_totals = {};
for (const t of long_tasks) for (const [k, v] of Object.entries(t.parts)) long_task_totals[k] = +((long_task_totals[k] || 0) + v).toFixed(1);
console.log(JSON.stringify({ file: path.basename(file), rate, width, height, query: extraQuery || '',
  loadavg: loadavg().map((x) => +x.toFixed(1)), faces: state.status.faces,
  first_object_ms: +(state.timing.firstObjectFrame - state.timing.firstBytes).toFixed(1),
  window_ms: +windowMs.toFixed(1), long_task_totals, long_tasks, threads }, null, 1));
