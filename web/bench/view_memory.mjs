// SPDX-License-Identifier: MIT
// The package's decoder (node) decoding a stream with a node table for one view, the file read
// as a range client reads it: in order up to the node table, then the ranges of the nodes the
// view needs. Prints the nodes applied, the bytes read and the WebAssembly memory it ended with
// (its linear memory never shrinks: the high-water mark).
//
//   node web/bench/view_memory.mjs STREAM.pmz EX,EY,EZ,TX,TY,TZ [PIXEL_ERROR=1] [WxH=1920x1080]
// PMZ_PACKAGE: the package's index.js (default web/dist/pkg/index.js).
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const [file, camera, pixelArg, sizeArg] = process.argv.slice(2);
if (!file || !camera) {
  console.error('usage: view_memory.mjs STREAM.pmz EX,EY,EZ,TX,TY,TZ [PIXEL_ERROR] [WxH]');
  process.exit(2);
}
const pkg = process.env.PMZ_PACKAGE ?? path.join(here, '..', 'dist', 'pkg', 'index.js');
const { createDecoder } = await import(pathToFileURL(pkg).href);
const bytes = readFileSync(file);
const c = camera.split(',').map(Number);
const [width, height] = (sizeArg ?? '1920x1080').split('x').map(Number);
const d = await createDecoder();
const started = performance.now();
let read = 0;
while (!d.nodeRange(1) && read < bytes.length) {
  if (d.feed(bytes.subarray(read, read + 65536)) !== 'ok') break;
  read = Math.min(bytes.length, read + 65536);
}
const view = await d.lookAt(c.slice(0, 3), c.slice(3), { width, height, pixelError: Number(pixelArg ?? 1) });
while (d.status === 'ok') {
  d.updateView(view);
  if (d.viewComplete()) break;
  const want = d.nodesToFetch();
  if (!want.length) break;
  for (const k of want) {
    const r = d.nodeRange(k);
    d.feedNode(k, bytes.subarray(r.offset, r.offset + r.size));
    read += r.size;
  }
}
console.log(JSON.stringify({
  file: path.basename(file), camera, complete: d.viewComplete(), error: d.error || undefined,
  nodes: d.nodesApplied(), node_count: d.nodeCount, faces_held: d.faceCount, bytes_read: read,
  bytes: bytes.length, wasm_memory: d._m.HEAPU8.buffer.byteLength,
  seconds: +((performance.now() - started) / 1000).toFixed(3),
}));
d.dispose();
