// SPDX-License-Identifier: MIT
// scripts/web.sh builds only what changed: run again with no change, it compiles, links and
// packs nothing (the objects, the wasm, the tarball and the viewer's files keep their mtimes)
// and says so, one "web: " line per step. (Under scripts/web.sh test both runs find the build
// just made; run alone, the first one may build.)
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { readdirSync, statSync } from 'node:fs';
import path from 'node:path';
import { test } from 'node:test';

import { rootDir, webDir } from './common.mjs';

function buildRun(env = {}, status = 0) {
  const r = spawnSync('bash', [path.join(rootDir, 'scripts', 'web.sh'), 'build'],
    { cwd: rootDir, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'], env: { ...process.env, ...env } });
  assert.equal(r.status, status, `scripts/web.sh build exited ${r.status}:\n${r.stdout}${r.stderr}`);
  return r;
}

// path -> mtime (ns) of every file under the build's outputs.
function outputTimes() {
  const times = {};
  const walk = (dir) => {
    for (const e of readdirSync(dir, { withFileTypes: true })) {
      const p = path.join(dir, e.name);
      if (e.isDirectory()) walk(p);
      else times[path.relative(webDir, p)] = statSync(p, { bigint: true }).mtimeNs;
    }
  };
  for (const dir of ['build/obj', 'build/obj-mt', 'build/mt', 'dist']) walk(path.join(webDir, dir));
  for (const f of ['pmz_wasm.wasm', 'pmz_wasm_mt.wasm'])
    times[`build/${f}`] = statSync(path.join(webDir, 'build', f), { bigint: true }).mtimeNs;
  return times;
}

test('a second scripts/web.sh run with no change rebuilds nothing and says so', () => {
  buildRun();
  const before = outputTimes();
  for (const dir of ['obj', 'obj-mt'])
    assert.ok(Object.keys(before).some((f) => f.startsWith(`build/${dir}/`) && f.endsWith('.o')),
      `no wasm objects under web/build/${dir}`);
  assert.ok(Object.keys(before).some((f) => /^dist\/pmz-decoder-.*\.tgz$/.test(f)), 'no tarball in web/dist');
  const again = buildRun();
  const after = outputTimes();
  const touched = Object.keys({ ...before, ...after }).filter((f) => before[f] !== after[f]);
  assert.deepEqual(touched, [], 'the second run rewrote these');
  const lines = again.stderr.trim().split('\n');
  for (const line of lines) assert.match(line, /^web: /, `a line not of a step: ${line}`);
  assert.ok(lines.includes('web: wasm: up to date (web/build/pmz_wasm.wasm)'), again.stderr);
  assert.ok(lines.some((l) => /^web: package: up to date/.test(l)), again.stderr);
  assert.ok(lines.some((l) => /^web: viewer: up to date/.test(l)), again.stderr);
  assert.doesNotMatch(again.stderr, /em\+\+|wasm-opt|packed/);
  assert.equal(again.stdout, '');
});

test('scripts/web.sh fails when the module and its loader pass the size ceiling', () => {
  const size = (r) => {
    const m = r.stderr.match(/^web: size: wasm (\d+) \+ glue (\d+) bytes \((\d+) gzip -9\)$/m);
    assert.ok(m, r.stderr);
    return { bytes: Number(m[1]) + Number(m[2]), gzip: Number(m[3]) };
  };
  const { bytes, gzip } = size(buildRun());
  buildRun({ PMZ_WASM_MAX_BYTES: String(bytes), PMZ_WASM_MAX_GZIP: String(gzip) });
  const over = buildRun({ PMZ_WASM_MAX_BYTES: String(bytes - 1) }, 1);
  assert.match(over.stderr, new RegExp(`^web: size: ${bytes} bytes \\(${gzip} gzip -9\\) above the ceiling of ${bytes - 1} `, 'm'));
  assert.match(buildRun({ PMZ_WASM_MAX_GZIP: String(gzip - 1) }, 1).stderr, /above the ceiling/);
});
