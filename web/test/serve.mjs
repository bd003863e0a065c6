// SPDX-License-Identifier: MIT
// A static server for web/dist/viewer on 127.0.0.1 whose /stream/NAME responses (streams and
// the textures beside them) are throttled to `bytesPerSecond` (chunks every 10 ms), with
// Content-Length. A request with `Range: bytes=a-b` (one range) gets a 206 with that slice and
// Content-Range, as static servers answer. streams[NAME]: a file, or {file, bytesPerSecond
// (Infinity: at once), delayMs (before the response starts), range ('honour' the default;
// 'ignore': a 200 with the whole file; 'wrongrange': the slice asked for, its Content-Range one
// byte later; 'stall': headers, then no body; 'front': ranges from byte 0 only, a 500 for others)}; server.requests[NAME]: when each
// request came (Date.now()); server.ranges[NAME]: the Range header of each ('' without). Under
// /coi/ the same files and streams come with the headers that make a page cross-origin
// isolated (COOP same-origin, COEP require-corp: shared memory, the threaded decoder).
import { copyFileSync, cpSync, createReadStream, mkdirSync, mkdtempSync, readFileSync, rmSync, statSync,
  writeFileSync } from 'node:fs';
import http from 'node:http';
import { tmpdir } from 'node:os';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.wasm': 'application/wasm', '.json': 'application/json', '.png': 'image/png' };

export function serveViewer(viewerDir, streams, bytesPerSecond) {
  const requests = {}, ranges = {};
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://127.0.0.1');
    let name = decodeURIComponent(url.pathname);
    if (name.startsWith('/coi/')) {
      name = name.slice(4);
      const writeHead = res.writeHead.bind(res);
      res.writeHead = (status, headers = {}) => writeHead(status, { ...headers,
        'cross-origin-opener-policy': 'same-origin', 'cross-origin-embedder-policy': 'require-corp' });
    }
    if (name.startsWith('/stream/') && streams[name.slice(8)]) {
      const entry = streams[name.slice(8)];
      const { file, bytesPerSecond: rate = bytesPerSecond, delayMs = 0, range: mode = 'honour' } =
        typeof entry === 'string' ? { file: entry } : entry;
      (requests[name.slice(8)] ??= []).push(Date.now());
      (ranges[name.slice(8)] ??= []).push(req.headers.range ?? '');
      const whole = readFileSync(file);
      let bytes = whole, status = 200;
      const headers = { 'content-type': TYPES[path.extname(name)] || 'application/octet-stream',
        'cache-control': 'no-store', 'accept-ranges': 'bytes' };
      const asked = /^bytes=(\d+)-(\d*)$/.exec(req.headers.range ?? '');
      if (asked && mode !== 'ignore') {
        const first = Number(asked[1]);
        if (mode === 'front' && first > 0) {
          res.writeHead(500).end();
          return;
        }
        const last = Math.min(whole.length - 1, asked[2] === '' ? Infinity : Number(asked[2]));
        if (first > last) {
          res.writeHead(416, { 'content-range': `bytes */${whole.length}` }).end();
          return;
        }
        const shift = mode === 'wrongrange' ? 1 : 0;
        bytes = whole.subarray(first, last + 1);
        status = 206;
        headers['content-range'] = `bytes ${first + shift}-${last + shift}/${whole.length}`;
      }
      const respond = () => {
        res.writeHead(status, { ...headers, 'content-length': bytes.length });
        if (mode === 'stall') {  // (the client's timeout ends it)
          res.flushHeaders();
          return;
        }
        const tick = 10;
        let at = 0;
        const start = Date.now();
        const send = () => {
          // Paced by the clock, not by timer counts: late timers send what is due.
          const due = Math.min(bytes.length, Math.round((Date.now() - start + tick) * rate / 1000));
          if (due > at) { res.write(bytes.subarray(at, due)); at = due; }
          if (at < bytes.length) setTimeout(send, tick); else res.end();
        };
        send();
      };
      if (delayMs > 0) setTimeout(respond, delayMs); else respond();
      return;
    }
    const file = path.join(viewerDir, path.normalize(name === '/' ? '/index.html' : name));
    if (!file.startsWith(viewerDir)) { res.writeHead(403).end(); return; }
    try {
      const size = statSync(file).size;
      res.writeHead(200, { 'content-type': TYPES[path.extname(file)] || 'application/octet-stream',
        'content-length': size });
      createReadStream(file).pipe(res);
    } catch {
      res.writeHead(404).end();
    }
  });
  server.requests = requests;
  server.ranges = ranges;
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

// WebGL through SwiftShader (with --disable-gpu too: the same renderer); callers add a fresh
// --user-data-dir.
export const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--use-gl=swiftshader',
  '--enable-unsafe-swiftshader', '--disable-background-networking', '--disable-component-update',
  '--disable-sync', '--no-first-run'];

// Headless Chromium (Debian's, or PMZ_CHROMIUM) with a fresh profile; close() ends it and
// removes the profile.
export async function launchChromium() {
  const profile = mkdtempSync(path.join(tmpdir(), 'pmz-chromium-'));
  const browser = await puppeteer.launch({ executablePath: process.env.PMZ_CHROMIUM || '/usr/bin/chromium',
    headless: true, args: [...CHROMIUM_ARGS, `--user-data-dir=${profile}`] });
  browser.closeAndClean = async () => {
    await browser.close();
    rmSync(profile, { recursive: true, force: true });
  };
  return browser;
}

// A static site in `site` for three's GLTFLoader in a page: the package in /pmz/ (three resolved
// by the page's import map), three, GLTFLoader and the relative import it makes in /jsm/, and an
// index.html with a 64 x 64 canvas. `webDir`: web/ (its dist/pkg and node_modules).
export function gltfLoaderSite(site, webDir) {
  const three = path.join(webDir, 'node_modules', 'three');
  mkdirSync(path.join(site, 'jsm', 'loaders'), { recursive: true });
  mkdirSync(path.join(site, 'jsm', 'utils'), { recursive: true });
  cpSync(path.join(webDir, 'dist', 'pkg'), path.join(site, 'pmz'), { recursive: true });
  copyFileSync(path.join(three, 'build', 'three.module.js'), path.join(site, 'three.module.js'));
  for (const f of ['loaders/GLTFLoader.js', 'utils/BufferGeometryUtils.js'])
    copyFileSync(path.join(three, 'examples', 'jsm', f), path.join(site, 'jsm', f));
  writeFileSync(path.join(site, 'index.html'), '<!doctype html><script type="importmap">' +
    '{"imports": {"three": "/three.module.js"}}</script><canvas width="64" height="64"></canvas>\n');
}

// The page's uncaught errors, console errors (but failed resource loads) and HTTP errors (but
// /favicon.ico), as they come.
export function pageErrors(page) {
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => {
    if (m.type() === 'error' && !m.text().startsWith('Failed to load resource')) errors.push(m.text());
  });
  page.on('response', (r) => {
    if (r.status() >= 400 && !r.url().endsWith('/favicon.ico')) errors.push(`${r.status()} ${r.url()}`);
  });
  return errors;
}
