// SPDX-License-Identifier: MIT
// What drawing a mesh costs in headless Chromium (Debian's chromium, WebGL2 through
// SwiftShader on the CPU): the viewer (web/dist/viewer) loads MESH.pmz at full speed, then
// draws the first F faces of the finished geometry for several F (window.pmzDrawCost:
// render() + a one-pixel readPixels, median of REPS), with the geomorph material and the plain one, at
// each viewport size. Tells whether a frame gap while streaming is the drawing itself.
//
//   node web/bench/draw_cost.mjs MESH.pmz [REPS=5] [SIZES=640x480,320x240] [FACES=1000,...]
import { mkdtempSync, rmSync } from 'node:fs';
import { loadavg, tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

import { CHROMIUM_ARGS, serveViewer } from '../test/serve.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [file, repsArg, sizesArg, facesArg] = process.argv.slice(2);
const reps = Number(repsArg || 5);
const sizes = (sizesArg || '640x480,320x240').split(',').map((s) => s.split('x').map(Number));
const faces = (facesArg || '1000,5000,20000,75000,300000,1200000').split(',').map(Number);
const viewerDir = process.env.PMZ_VIEWER_DIR || path.join(here, '..', 'dist', 'viewer');
const server = await serveViewer(path.resolve(viewerDir), { 'mesh.pmz': path.resolve(file) }, 1e9);
const profile = mkdtempSync(path.join(tmpdir(), 'pmz-bench-chromium-'));
const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
  protocolTimeout: 900000, args: [...CHROMIUM_ARGS, `--user-data-dir=${profile}`] });
const rows = [];
try {
  for (const [width, height] of sizes) {
    const page = await browser.newPage();
    await page.setViewport({ width, height });
    await page.goto(`http://127.0.0.1:${server.address().port}/index.html?src=/stream/mesh.pmz`);
    await page.waitForFunction(() => window.pmzStatus.complete || window.pmzStatus.error,
      { timeout: 600000, polling: 200 });
    const env = await page.evaluate(() => ({ dpr: window.devicePixelRatio, renderer: window.pmzRenderer }));
    for (const morphing of [true, false]) {
      const r = await page.evaluate((f, n, m) => window.pmzDrawCost(f, n, m), faces, reps, morphing);
      for (const x of r.rows) rows.push({ viewport: `${width}x${height}`, ...env, canvas: r.canvas,
        material: morphing ? 'geomorph' : 'plain', ...x });
    }
    await page.close();
  }
} finally {
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
  server.close();
}
console.log(JSON.stringify({ file: path.basename(file), reps, loadavg: loadavg().map((x) => +x.toFixed(1)), rows }, null, 1));
