// SPDX-License-Identifier: MIT
// The JavaScript API (node): the packed package decodes bit-identically to the native decoder,
// any byte slicing gives the same mesh, and damaged or hostile streams give error names and
// one-line errors, never exceptions or hangs.
import assert from 'node:assert/strict';
import { existsSync, readdirSync, readFileSync, statSync } from 'node:fs';
import path from 'node:path';
import { test } from 'node:test';

import { demoPmz, importPackage, nativeDecode, rootDir, sameBits } from './common.mjs';

const samplePmz = path.join(rootDir, 'tests', 'data', 'sample.pmz');
// A speed-level stream (format 10.0's level 1) beside two default-level ones.
const speedPmz = path.join(rootDir, 'tests', 'conformance', 'vectors', 'torus-speed.pmz');
const files = [samplePmz, demoPmz(), speedPmz];
const levelOf = (file) => (file === speedPmz ? 1 : 0);

function copyMesh(d) {
  return { positions: d.positions().slice(), indices: d.indices().slice() };
}

async function decodeAll(bytes, sliceSizes) {
  const { createDecoder } = await importPackage();
  const d = await createDecoder();
  let at = 0, k = 0;
  while (at < bytes.length) {
    const n = sliceSizes[k++ % sliceSizes.length];
    assert.equal(d.feed(bytes.subarray(at, at + n)), 'ok');
    at += n;
    d.refine(97);  // interleaved, as a viewer does
  }
  assert.equal(d.finish(), 'ok');
  d.refine();
  assert.equal(d.status, 'ok');
  assert.equal(d.error, '');
  const mesh = copyMesh(d);
  const info = d.info();
  d.dispose();
  return { mesh, info };
}

test('the package installs from the tarball and exports the contract', async () => {
  const pkg = await importPackage();
  assert.equal(typeof pkg.createDecoder, 'function');
  const d = await pkg.createDecoder();
  for (const m of ['feed', 'finish', 'refine', 'setFaceTarget', 'positions', 'indices', 'dispose'])
    assert.equal(typeof d[m], 'function', m);
  assert.equal(d.faceCount, 0);
  assert.equal(d.vertexCount, 0);
  assert.equal(d.error, '');
  d.dispose();
});

for (const file of files) {
  const name = path.basename(path.dirname(file)) + '/' + path.basename(file);
  test(`full decode of ${name} is bit-identical to pmz-decode`, async () => {
    const bytes = readFileSync(file);
    const { mesh, info } = await decodeAll(bytes, [bytes.length]);
    const native = nativeDecode(file);
    assert.equal(mesh.indices.length / 3, info.fullFaces);
    assert.equal(info.level, levelOf(file));
    assert.equal(mesh.positions.length, native.positions.length);
    assert.ok(sameBits(mesh.positions, native.positions), 'positions differ');
    assert.ok(sameBits(mesh.indices, native.indices), 'indices differ');
  });

  test(`levels of ${name} (setFaceTarget, coarsen) match pmz-decode --faces`, async () => {
    const { createDecoder } = await importPackage();
    const bytes = readFileSync(file);
    const d = await createDecoder();
    assert.equal(d.feed(bytes), 'ok');
    assert.equal(d.finish(), 'ok');
    const full = d.info().fullFaces;
    d.refine();
    // Down from the finest level (coarsening), then up again (refining).
    for (const target of [Math.floor(full / 10), Math.floor(full / 2), 1, full - 1]) {
      d.setFaceTarget(target);
      assert.ok(d.faceCount >= Math.min(target, full));
      const native = nativeDecode(file, ['--faces', String(target)]);
      assert.ok(sameBits(d.positions(), native.positions), `positions at ${target} faces`);
      assert.ok(sameBits(d.indices(), native.indices), `indices at ${target} faces`);
    }
    d.dispose();
  });

  test(`every byte slicing of ${name} gives the same mesh`, async () => {
    const bytes = readFileSync(file);
    const whole = (await decodeAll(bytes, [bytes.length])).mesh;
    const slicings = [[1], [7], [4096], [3, 1000, 1, 65536, 17], [64 * 1024]];
    if (bytes.length > 10000) slicings.shift();  // 1-byte slices only for the small file
    for (const sizes of slicings) {
      const { mesh } = await decodeAll(bytes, sizes);
      assert.ok(sameBits(mesh.positions, whole.positions), `positions, slices ${sizes}`);
      assert.ok(sameBits(mesh.indices, whole.indices), `indices, slices ${sizes}`);
    }
  });
}

test('the change report covers every difference while streaming', async () => {
  const { createDecoder } = await importPackage();
  const bytes = readFileSync(demoPmz());
  const d = await createDecoder();
  let pos = new Float32Array(0), idx = new Uint32Array(0), steps = 0;
  for (let at = 0; at < bytes.length; at += 8192) {
    assert.equal(d.feed(bytes.subarray(at, at + 8192)), 'ok');
    while (d.refine(500) > 0 || (at + 8192 >= bytes.length && d.splitsApplied < d.splitsAvailable)) {
      const c = d.changes();
      const p = d.positions(), t = d.indices();
      const np = new Float32Array(p.length), ni = new Uint32Array(t.length);
      if (c.all) { np.set(p); ni.set(t); } else {
        np.set(pos.subarray(0, Math.min(pos.length, np.length)));
        ni.set(idx.subarray(0, Math.min(idx.length, ni.length)));
        np.set(p.subarray(3 * c.vertexBegin), 3 * c.vertexBegin);
        ni.set(t.subarray(3 * c.faceBegin), 3 * c.faceBegin);
        for (const f of c.modifiedFaces) ni.set(t.subarray(3 * f, 3 * f + 3), 3 * f);
      }
      assert.ok(sameBits(np, p) && sameBits(ni, t), `after step ${steps}`);
      pos = np; idx = ni; ++steps;
      d.clearChanges();
    }
  }
  assert.equal(d.finish(), 'ok');
  assert.equal(d.faceCount, d.info().fullFaces);
  assert.ok(steps > 10);
  d.dispose();
});

// CRC-32 as the container's (zlib's polynomial), to damage chunk payloads past the checksum.
const crcTable = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32(bytes, crc = 0) {
  crc = ~crc >>> 0;
  for (const b of bytes) crc = (crcTable[(crc ^ b) & 0xff] ^ (crc >>> 8)) >>> 0;
  return ~crc >>> 0;
}
// Chunks after the 8-byte signature: type, varint size, u32le CRC, payload.
function chunks(b) {
  const out = [];
  for (let at = 8; at < b.length;) {
    let size = 0, shift = 0, i = at + 1;
    for (;;) { const x = b[i++]; size += (x & 0x7f) * 2 ** shift; shift += 7; if (!(x & 0x80)) break; }
    out.push({ at, crcAt: i, payload: i + 4, size });
    at = i + 4 + size;
  }
  return out;
}
function repairCrc(b, c) {
  const crc = crc32(b.subarray(c.payload, c.payload + c.size), crc32(b.subarray(c.at, c.crcAt)));
  new DataView(b.buffer, b.byteOffset).setUint32(c.crcAt, crc, true);
}

// Decodes hostile bytes in 1000-byte slices with refinement; returns the outcome. Throws only
// if the API throws (a test failure).
async function decodeHostile(bytes, options) {
  const { createDecoder, STATUS_NAMES } = await importPackage();
  const d = await createDecoder(options);
  let status = 'ok';
  for (let at = 0; status === 'ok' && at < bytes.length; at += 1000) {
    status = d.feed(bytes.subarray(at, at + 1000));
    d.refine(1000);
  }
  if (status === 'ok') status = d.finish();
  d.refine();
  d.setFaceTarget(1);
  d.refine();
  const final = d.status;
  assert.ok(STATUS_NAMES.includes(status), status);
  assert.ok(STATUS_NAMES.includes(final), final);
  const error = d.error;
  if (final !== 'ok' || status !== 'ok') {
    assert.ok(error.length > 0, 'an error without a message');
    assert.ok(!error.includes('\n'), `not one line: ${error}`);
  }
  assert.ok(d.faceCount * 3 === d.indices().length);
  const nv = d.vertexCount;
  for (const i of d.indices()) assert.ok(i < nv, 'index out of range');
  d.dispose();
  return { status, final, error };
}

test('hostile streams give error names and one-line errors', async () => {
  const good = new Uint8Array(readFileSync(samplePmz));
  const seen = new Set();
  const note = (r) => seen.add(r.status === 'ok' ? r.final : r.status);
  // Every truncation.
  for (let n = 0; n < good.length; n += 1) note(await decodeHostile(good.subarray(0, n)));
  // Each byte of each chunk's payload and frame damaged, with and without its CRC repaired.
  for (const c of chunks(good)) {
    for (let i = c.at; i < c.payload + c.size; ++i) {
      for (const x of [0x01, 0x80, 0xff]) {
        const b = good.slice();
        b[i] ^= x;
        note(await decodeHostile(b));
        if (i >= c.payload) {
          repairCrc(b, c);
          note(await decodeHostile(b));
        }
      }
    }
  }
  // Junk, an empty stream, a signature alone, and limits below the mesh.
  note(await decodeHostile(new TextEncoder().encode('this is not a pmz stream')));
  note(await decodeHostile(new Uint8Array(0)));
  note(await decodeHostile(good.subarray(0, 8)));
  const limited = await decodeHostile(good, { maxVertices: 10 });
  assert.equal(limited.status, 'limit_exceeded');
  note(limited);
  // Hostile files kept on disk by the native suites, when present (tests/conformance).
  const dir = path.join(rootDir, 'tests', 'conformance');
  const walk = (p) => statSync(p).isDirectory() ? readdirSync(p).flatMap((f) => walk(path.join(p, f))) : [p];
  if (existsSync(dir))
    for (const f of walk(dir).filter((f) => f.endsWith('.pmz'))) note(await decodeHostile(readFileSync(f)));
  for (const s of ['truncated', 'bad_magic', 'bad_checksum', 'corrupt', 'limit_exceeded'])
    assert.ok(seen.has(s), `no case gave ${s}: ${[...seen]}`);
});

// After an error the splits that arrived before the damage are still applied: refineFor()
// within its budget (not one batch and stop), as refine() does.
test('refineFor() after a truncation applies what arrived within its budget', async () => {
  const { createDecoder } = await importPackage();
  const bytes = readFileSync(demoPmz());
  const d = await createDecoder();
  assert.equal(d.feed(bytes.subarray(0, 60000)), 'ok');
  assert.equal(d.finish(), 'truncated');
  const available = d.splitsAvailable;
  assert.ok(available > 10000, `${available} splits available`);
  assert.equal(d.refineFor(60000), available);
  assert.equal(d.splitsApplied, available);
  assert.equal(d.refineFor(60000), 0);
  assert.equal(d.status, 'truncated');
  d.dispose();
});

test('a decoder after dispose() throws a plain error, others keep working', async () => {
  const { createDecoder } = await importPackage();
  const a = await createDecoder(), b = await createDecoder();
  a.dispose();
  assert.throws(() => a.feed(new Uint8Array(4)), /dispose/);
  assert.equal(b.feed(readFileSync(samplePmz)), 'ok');
  assert.equal(b.finish(), 'ok');
  b.refine();
  assert.equal(b.faceCount, 128);
  b.dispose();
});
