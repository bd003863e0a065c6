// SPDX-License-Identifier: MIT
// Decode speed, side by side in one run: the native library (bench-stream: the whole file fed,
// refined once, process CPU time), pmz-decoder's WebAssembly build in node, and npm draco3d's
// WebAssembly decoder on the same mesh's .drc (positions and indices out). Each measurement is
// a fresh process; the three alternate, ROUNDS rounds, medians. Also the sizes of both decoders.
//
//   node web/bench/decode_speed.mjs MESH.pmz MESH.drc [ROUNDS=5] [PKG_DIR=web/dist/pkg]
//
// Times are CPU seconds of the decoding process (user + system, which a loaded machine does not
// inflate as it does wall time), from the bytes in memory to positions and indices out; module
// instantiation (wasm compile) is reported apart. Wall seconds beside them. The like-for-like
// figure on a quiet machine is wall time (wasm_over_native_wall): the native decode runs on one
// thread, while node's process CPU also counts V8's background threads (TurboFan tiering up the
// wasm functions, GC), which run beside the decode on another core; under load, where wall time
// waits for a core, the CPU ratio is the steadier one (docs/benchmarks.md).
import { execFileSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { gzipSync } from 'node:zlib';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..', '..');
const cpu = () => { const u = process.cpuUsage(); return (u.user + u.system) / 1e6; };
const faults = () => process.resourceUsage().minorPageFault;  // first touches of new pages

async function runWasm(file, pkgDir) {
  const { createDecoder } = await import(pathToFileURL(path.join(pkgDir, 'index.js')).href);
  const bytes = readFileSync(file);
  const c0 = cpu(), w0 = performance.now();
  const d = await createDecoder();
  const c1 = cpu(), w1 = performance.now(), f1 = faults();
  if (d.feed(bytes) !== 'ok' || d.finish() !== 'ok') throw new Error(d.error);
  d.refine();
  if (d.status !== 'ok') throw new Error(d.error);
  const positions = d.positions().slice(), indices = d.indices().slice();
  const c2 = cpu(), w2 = performance.now();
  return { faces: indices.length / 3, vertices: positions.length / 3, cpu_s: c2 - c1,
    wall_s: (w2 - w1) / 1000, init_cpu_s: c1 - c0, page_faults: faults() - f1 };
}

async function runDraco(file) {
  const draco3d = createRequire(import.meta.url)(path.join(root, 'web', 'node_modules', 'draco3d'));
  const bytes = readFileSync(file);
  const c0 = cpu(), w0 = performance.now();
  const m = await draco3d.createDecoderModule({});
  const c1 = cpu(), w1 = performance.now(), f1 = faults();
  const decoder = new m.Decoder(), buffer = new m.DecoderBuffer(), mesh = new m.Mesh();
  buffer.Init(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.length), bytes.length);
  const status = decoder.DecodeBufferToMesh(buffer, mesh);
  if (!status.ok()) throw new Error(status.error_msg());
  // As three's DRACOLoader: indices and float positions for all points.
  const nf = mesh.num_faces(), np = mesh.num_points();
  const ip = m._malloc(nf * 12);
  decoder.GetTrianglesUInt32Array(mesh, nf * 12, ip);
  const indices = new Uint32Array(m.HEAPF32.buffer, ip, nf * 3).slice();
  const attr = decoder.GetAttribute(mesh, decoder.GetAttributeId(mesh, m.POSITION));
  const pp = m._malloc(np * 12);
  decoder.GetAttributeDataArrayForAllPoints(mesh, attr, m.DT_FLOAT32, np * 12, pp);
  const positions = new Float32Array(m.HEAPF32.buffer, pp, np * 3).slice();
  const c2 = cpu(), w2 = performance.now();
  return { faces: indices.length / 3, vertices: positions.length / 3, cpu_s: c2 - c1,
    wall_s: (w2 - w1) / 1000, init_cpu_s: c1 - c0, page_faults: faults() - f1 };
}

function runNative(file) {
  const bin = path.join(process.env.PMZ_BENCH_BIN || path.join(root, 'build', 'bench'), 'bench-stream');
  const size = readFileSync(file).length;
  const out = JSON.parse(execFileSync(bin, [file, '--slice', String(size), '--refine', '0']).toString());
  return { faces: out.faces, cpu_s: out.cpu_s, wall_s: out.wall_s };
}

const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };

if (process.argv[2] === 'child') {
  const [, , , kind, file, pkgDir] = process.argv;
  const r = kind === 'wasm' ? await runWasm(file, pkgDir) : await runDraco(file);
  console.log(JSON.stringify(r));
} else {
  const [pmz, drc] = process.argv.slice(2, 4);
  const rounds = Number(process.argv[4] || 5);
  const pkgDir = path.resolve(process.argv[5] || path.join(root, 'web', 'dist', 'pkg'));
  const child = (kind, file) => JSON.parse(execFileSync(process.execPath,
    [fileURLToPath(import.meta.url), 'child', kind, file, pkgDir]).toString());
  const runs = { native: [], wasm: [], draco: [] };
  for (let r = 0; r < rounds; ++r) {
    runs.native.push(runNative(pmz));
    runs.wasm.push(child('wasm', pmz));
    runs.draco.push(child('draco', drc));
  }
  const size = (f) => readFileSync(f).length;
  const gz = (fs) => gzipSync(Buffer.concat(fs.map((f) => readFileSync(f))), { level: 9 }).length;
  const ours = [path.join(pkgDir, 'pmz_wasm.wasm'), path.join(pkgDir, 'pmz_wasm.js')];
  const dd = path.join(root, 'web', 'node_modules', 'draco3d');
  const theirs = [path.join(dd, 'draco_decoder.wasm'), path.join(dd, 'draco_decoder_nodejs.js')];
  const report = {
    pmz: path.basename(pmz), pmz_bytes: size(pmz), drc: path.basename(drc), drc_bytes: size(drc),
    rounds, loadavg: (await import('node:os')).loadavg().map((x) => +x.toFixed(1)),
  };
  for (const [k, v] of Object.entries(runs)) {
    report[k] = { faces: v[0].faces, cpu_s: +median(v.map((x) => x.cpu_s)).toFixed(4),
      wall_s: +median(v.map((x) => x.wall_s)).toFixed(4), cpu_all: v.map((x) => +x.cpu_s.toFixed(4)) };
    if (v[0].init_cpu_s !== undefined) report[k].init_cpu_s = +median(v.map((x) => x.init_cpu_s)).toFixed(4);
    if (v[0].page_faults !== undefined) report[k].page_faults = median(v.map((x) => x.page_faults));
  }
  report.wasm_over_native_cpu = +(report.wasm.cpu_s / report.native.cpu_s).toFixed(3);
  report.wasm_over_native_wall = +(report.wasm.wall_s / report.native.wall_s).toFixed(3);
  report.size = {
    pmz_wasm: size(ours[0]), pmz_glue: size(ours[1]), pmz_total: size(ours[0]) + size(ours[1]),
    pmz_gzip9: gz(ours),
    draco_wasm: size(theirs[0]), draco_glue: size(theirs[1]), draco_gzip9: gz(theirs),
  };
  console.log(JSON.stringify(report, null, 1));
}
