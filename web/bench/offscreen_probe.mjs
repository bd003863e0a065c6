// SPDX-License-Identifier: MIT
// Does drawing in a worker keep the page's frames in headless Chromium with SwiftShader? A
// minimal page (offscreen_probe/) draws a grid of N faces every frame with the viewer's material
// on the page's thread (page), in a worker on the canvas transferred to it (worker: the page
// only updates a text overlay), or not at all (none: what the machine alone does to the page's
// frames), with one more worker busy in 8 ms slices as the decoding worker is. Reported per run
// after the first 0.5 s: the page's requestAnimationFrame gaps (median, p95, max, how many over
// 50 ms), the drawing worker's own frame intervals, and the page's long tasks.
//
//   node web/bench/offscreen_probe.mjs [MODES=none,worker,page] [FACES=2000,20000,75000] [ROUNDS=3]
//                                      [WIDTHxHEIGHT=640x480]
// Runs alternate the modes for each face count, round after round.
import { copyFileSync, mkdtempSync, readdirSync, rmSync } from 'node:fs';
import { loadavg, tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

import { CHROMIUM_ARGS, serveViewer } from '../test/serve.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [modesArg, facesArg, roundsArg, sizeArg] = process.argv.slice(2);
const modes = (modesArg || 'none,worker,page').split(',');
const sizes = (facesArg || '2000,20000,75000').split(',').map(Number);
const rounds = Number(roundsArg || 3);
const [width, height] = (sizeArg || '640x480').split('x').map(Number);
const site = mkdtempSync(path.join(tmpdir(), 'pmz-probe-site-'));
for (const f of readdirSync(path.join(here, 'offscreen_probe'))) copyFileSync(path.join(here, 'offscreen_probe', f), path.join(site, f));
copyFileSync(path.join(here, '..', 'node_modules', 'three', 'build', 'three.module.js'), path.join(site, 'three.module.js'));
const server = await serveViewer(site, {}, 1e9);
const SETTLE_MS = 500;  // start-up and shader compilation
const stats = (times) => {
  const t = times.filter((x) => x > times[0] + SETTLE_MS);
  const gaps = t.slice(1).map((x, i) => x - t[i]).sort((a, b) => a - b);
  if (!gaps.length) return null;
  return { frames: gaps.length, median: +gaps[gaps.length >> 1].toFixed(1), p95: +gaps[Math.floor(0.95 * gaps.length)].toFixed(1),
    max: +gaps[gaps.length - 1].toFixed(1), over_50ms: gaps.filter((g) => g > 50).length };
};
const runs = [];
try {
  for (let r = 0; r < rounds; ++r) {
    for (const faces of sizes) {
      for (const mode of modes) {
        const profile = mkdtempSync(path.join(tmpdir(), 'pmz-probe-'));
        const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
          args: [...CHROMIUM_ARGS, `--user-data-dir=${profile}`] });
        try {
          const page = await browser.newPage();
          await page.setViewport({ width, height });
          await page.goto(`http://127.0.0.1:${server.address().port}/index.html?mode=${mode}&faces=${faces}`);
          await page.waitForFunction(() => window.probe && window.probe.done, { timeout: 120000, polling: 200 });
          const p = await page.evaluate(() => window.probe);
          const after = p.page.length ? p.page[0] + SETTLE_MS : 0;
          const tasks = p.longTasks.filter((x) => x.start >= after);
          const run = { mode, faces, loadavg: +loadavg()[0].toFixed(1), page: stats(p.page), worker: stats(p.worker),
            long_tasks: tasks.length, long_task_max_ms: +Math.max(0, ...tasks.map((x) => x.duration)).toFixed(1),
            error: p.error };
          runs.push(run);
          console.error(JSON.stringify(run));
        } finally {
          await browser.close();
          rmSync(profile, { recursive: true, force: true });
        }
      }
    }
  }
} finally {
  server.close();
  rmSync(site, { recursive: true, force: true });
}
// Per mode and size, the median over the rounds of each figure.
const median = (xs) => {
  const v = xs.filter((x) => typeof x === 'number').sort((a, b) => a - b);
  return v.length ? v[(v.length - 1) >> 1] : null;
};
const medians = [];
for (const faces of sizes) {
  for (const mode of modes) {
    const rs = runs.filter((x) => x.mode === mode && x.faces === faces);
    const pick = (k, f) => median(rs.map((x) => x[k] && x[k][f]));
    medians.push({ mode, faces, loadavg: median(rs.map((x) => x.loadavg)), page_gap_median_ms: pick('page', 'median'),
      page_gap_max_ms: pick('page', 'max'), page_gaps_over_50ms: pick('page', 'over_50ms'), page_frames: pick('page', 'frames'),
      worker_frame_median_ms: pick('worker', 'median'), worker_frame_max_ms: pick('worker', 'max'),
      long_tasks: median(rs.map((x) => x.long_tasks)) });
  }
}
console.log(JSON.stringify({ width, height, rounds, loadavg: loadavg().map((x) => +x.toFixed(1)), medians, runs }, null, 1));
