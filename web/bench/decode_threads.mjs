// SPDX-License-Identifier: MIT
// Decode speed of pmz-decoder in node with one worker (the single-threaded module) against N
// (the threaded module: createDecoder({ workers: N })): each measurement a fresh process, the
// two alternate, ROUNDS rounds, medians. Wall seconds from the bytes in memory to positions and
// indices out (feed, refine(), copies); instantiation (for N: the threaded module and its N - 1
// workers) reported apart. Checks that both give the same mesh. The same rounds time the native
// decoder with --threads 1 and N as a control of what the machine's free cores allowed then
// (build/bin/pmz-decode, or PMZ_BIN/pmz-decode; its wall time, the process's start included).
//
//   node web/bench/decode_threads.mjs MESH.pmz [ROUNDS=5] [N=2] [PKG_DIR=web/dist/pkg]
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..', '..');
const cpu = () => { const u = process.cpuUsage(); return (u.user + u.system) / 1e6; };
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };

async function run(file, workers, pkgDir) {
  const { createDecoder } = await import(pathToFileURL(path.join(pkgDir, 'index.js')).href);
  const bytes = readFileSync(file);
  const w0 = performance.now();
  const d = await createDecoder({ workers });
  const w1 = performance.now(), c1 = cpu();
  if (d.feed(bytes) !== 'ok' || d.finish() !== 'ok') throw new Error(d.error);
  d.refine();
  if (d.status !== 'ok') throw new Error(d.error);
  const positions = d.positions().slice(), indices = d.indices().slice();
  const w2 = performance.now(), c2 = cpu();
  const hash = createHash('sha256').update(new Uint8Array(positions.buffer))
    .update(new Uint8Array(indices.buffer)).digest('hex').slice(0, 16);
  return { workers: d.workers, faces: indices.length / 3, nodes: d.nodeCount, wall_s: (w2 - w1) / 1000,
    cpu_s: c2 - c1, init_s: (w1 - w0) / 1000, threads_started: d._m.threadStarts ?? 0, hash };
}

if (process.argv[2] === 'child') {
  const [, , , file, workers, pkgDir] = process.argv;
  console.log(JSON.stringify(await run(file, Number(workers), pkgDir)));
  process.exit(0);
} else {
  const file = process.argv[2];
  const rounds = Number(process.argv[3] || 5), n = Number(process.argv[4] || 2);
  const pkgDir = path.resolve(process.argv[5] || path.join(root, 'web', 'dist', 'pkg'));
  const child = (workers) => JSON.parse(execFileSync(process.execPath,
    [fileURLToPath(import.meta.url), 'child', file, String(workers), pkgDir]).toString());
  const date = new Date().toISOString();
  const load = [os.loadavg()];
  const decode = path.join(process.env.PMZ_BIN || path.join(root, 'build', 'bin'), 'pmz-decode');
  const native = (threads) => {
    const t = performance.now();
    execFileSync(decode, [file, '-o', '/dev/null', '--format', 'ply', '--threads', String(threads)],
      { stdio: ['ignore', 'ignore', 'pipe'] });
    return { wall_s: (performance.now() - t) / 1000 };
  };
  const runs = { one: [], many: [], native_one: [], native_many: [] };
  for (let r = 0; r < rounds; ++r) {
    runs.one.push(child(1));
    runs.many.push(child(n));
    runs.native_one.push(native(1));
    runs.native_many.push(native(n));
    load.push(os.loadavg());
  }
  const hashes = new Set([...runs.one, ...runs.many].map((x) => x.hash));
  const wall = (v) => ({ wall_s: +median(v.map((x) => x.wall_s)).toFixed(4), wall_all: v.map((x) => +x.wall_s.toFixed(4)) });
  if (hashes.size !== 1) throw new Error(`the meshes differ: ${[...hashes].join(' ')}`);
  const sum = (v) => ({ workers: v[0].workers, wall_s: +median(v.map((x) => x.wall_s)).toFixed(4),
    cpu_s: +median(v.map((x) => x.cpu_s)).toFixed(4), init_s: +median(v.map((x) => x.init_s)).toFixed(4),
    threads_started: v[0].threads_started, wall_all: v.map((x) => +x.wall_s.toFixed(4)) });
  const report = { pmz: path.basename(file), faces: runs.one[0].faces, nodes: runs.one[0].nodes, rounds,
    date, cores: os.availableParallelism ? os.availableParallelism() : os.cpus().length,
    loadavg_1min: load.map((l) => +l[0].toFixed(2)), one: sum(runs.one), many: sum(runs.many) };
  report.speedup_wall = +(report.one.wall_s / report.many.wall_s).toFixed(3);
  report.native_one = wall(runs.native_one);
  report.native_many = wall(runs.native_many);
  report.native_speedup_wall = +(report.native_one.wall_s / report.native_many.wall_s).toFixed(3);
  console.log(JSON.stringify(report, null, 1));
}
