// Attribute arrays of the JavaScript API (format 8.0): texture coordinates, normals, colours,
// wedges and materials are bit-identical to the native decoder's (pmz-dump-arrays, the C API)
// for every byte slicing and at coarser levels; the change report covers the wedges; a
// geometry-only stream gives empty attribute arrays.
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { test } from 'node:test';

import { assimpTextured, encodeNative, importPackage, nativeArrays, rootDir, sameBits,
  writeColoredTorus, writeTexturedTorus } from './common.mjs';

const work = mkdtempSync(path.join(tmpdir(), 'pmz-web-attr-'));
const once = (f) => { let r; return () => (r === undefined ? (r = f()) : r); };
const streams = {
  'seamed textured torus': once(() => encodeNative(writeTexturedTorus(work), path.join(work, 'textured.pmz'))),
  'coloured torus with normals': once(() => encodeNative(writeColoredTorus(work), path.join(work, 'colored.pmz'))),
  'assimp OBJ/spider.obj': once(() => assimpTextured() && encodeNative(assimpTextured(), path.join(work, 'spider.pmz'))),
};

// The decoder's arrays as raw bytes, named as pmz-dump-arrays names them (copies).
function jsArrays(d) {
  const bytes = (a) => new Uint8Array(a.buffer, a.byteOffset, a.byteLength).slice();
  const out = { positions: bytes(d.positions()), indices: bytes(d.indices()) };
  if (d.wedgeCount) {
    out.wedgeVertices = bytes(d.wedgeVertices());
    out.wedgePositions = bytes(d.wedgePositions());
    out.wedgeIndices = bytes(d.wedgeIndices());
    for (let s = 0; s < d.texcoordSetCount; ++s) out['texcoords' + s] = bytes(d.texcoords(s));
    if (d.normals().length) out.normals = bytes(d.normals());
    if (d.colors().length) out.colors = bytes(d.colors());
  }
  if (d.faceMaterials().length) out.faceMaterials = bytes(d.faceMaterials());
  return out;
}

function assertSameAsNative(d, native, what) {
  const h = native.header;
  assert.equal(d.vertexCount, h.vertices, `${what}: vertices`);
  assert.equal(d.faceCount, h.faces, `${what}: faces`);
  assert.equal(d.wedgeCount, h.wedges, `${what}: wedges`);
  assert.equal(d.texcoordSetCount, h.texcoordSets, `${what}: texture coordinate sets`);
  assert.equal(d.colorComponents, h.colorComponents, `${what}: colour components`);
  assert.equal(d.materialCount, h.materials.length, `${what}: materials`);
  const mats = d.materials();
  h.materials.forEach((m, i) => {
    assert.equal(mats[i].name, m.name);
    assert.equal(mats[i].baseColorTexture, m.baseColorTexture);
    assert.equal(mats[i].normalTexture, m.normalTexture);
    assert.deepEqual(mats[i].baseColor, m.baseColor.map(Math.fround));
  });
  const mine = jsArrays(d);
  assert.deepEqual(Object.keys(mine).sort(), Object.keys(native.arrays).sort(), `${what}: arrays`);
  for (const [name, bytes] of Object.entries(native.arrays))
    assert.ok(sameBits(mine[name], bytes), `${what}: ${name} differs`);
}

async function decodeSliced(bytes, sizes) {
  const { createDecoder } = await importPackage();
  const d = await createDecoder();
  for (let at = 0, k = 0; at < bytes.length; ) {
    const n = sizes[k++ % sizes.length];
    assert.equal(d.feed(bytes.subarray(at, at + n)), 'ok');
    at += n;
    d.refine(61);  // interleaved, as a viewer does
  }
  assert.equal(d.finish(), 'ok');
  d.refine();
  assert.equal(d.status, 'ok');
  return d;
}

for (const [name, make] of Object.entries(streams)) {
  test(`${name}: attribute arrays bit-identical to the native decoder's, any slicing`, async (t) => {
    const file = make();
    if (!file) return t.skip('corpus-assimp/ missing (scripts/fetch_assimp_models.sh)');
    const bytes = readFileSync(file);
    const native = nativeArrays(file);
    assert.ok(native.header.wedges > 0, 'the native decoder sees no attributes');
    for (const sizes of [[bytes.length], [1], [7], [4096], [3, 1000, 1, 65536, 17]]) {
      const d = await decodeSliced(bytes, sizes);
      assertSameAsNative(d, native, `slices ${sizes}`);
      d.dispose();
    }
  });

  test(`${name}: attribute arrays at coarser levels match the native decoder's`, async (t) => {
    const file = make();
    if (!file) return t.skip('corpus-assimp/ missing (scripts/fetch_assimp_models.sh)');
    const d = await decodeSliced(readFileSync(file), [8192]);
    const full = d.info().fullFaces;
    // Down from the finest level (coarsening), then up again (refining).
    for (const target of [Math.floor(full / 10), Math.floor(full / 2), 1, full - 1]) {
      d.setFaceTarget(target);
      assertSameAsNative(d, nativeArrays(file, target), `${target} faces`);
    }
    d.dispose();
  });

  test(`${name}: the change report covers every wedge and attribute change`, async (t) => {
    const file = make();
    if (!file) return t.skip('corpus-assimp/ missing (scripts/fetch_assimp_models.sh)');
    const { createDecoder } = await importPackage();
    const bytes = readFileSync(file);
    const d = await createDecoder();
    // Per-wedge arrays (items of `per` elements) and per-face arrays, kept up to date from the
    // change report only and compared with the decoder's after every step.
    const perWedge = { wedgePositions: 3, wedgeVertices: 1, texcoords: 2, normals: 3, colors: 0 };
    const perFace = { indices: 3, wedgeIndices: 3, faceMaterials: 1 };
    const get = (k) => (k === 'texcoords' ? d.texcoords(0) : d[k]());
    const mirror = {};
    let steps = 0;
    const step = () => {
      const c = d.changes();
      const arrays = [
        ...Object.entries(perWedge).map(([k, n]) => [k, k === 'colors' ? d.colorComponents : n, c.wedgeBegin, false]),
        ...Object.entries(perFace).map(([k, n]) => [k, n, c.faceBegin, true]),
      ];
      for (const [k, n, begin, perFaceArray] of arrays) {
        const now = get(k), old = mirror[k];
        const next = new now.constructor(now.length);
        if (c.all || !old || now.length === 0) {  // (an array the stream does not have: empty)
          next.set(now);
        } else {
          next.set(old.subarray(0, Math.min(old.length, next.length)));
          next.set(now.subarray(n * begin), n * begin);
          if (perFaceArray)
            for (const f of c.modifiedFaces) next.set(now.subarray(n * f, n * f + n), n * f);
        }
        assert.ok(sameBits(next, now), `${k} after step ${steps}`);
        mirror[k] = next;
      }
      ++steps;
      d.clearChanges();
    };
    for (let at = 0; at < bytes.length; at += 2048) {
      assert.equal(d.feed(bytes.subarray(at, at + 2048)), 'ok');
      while (d.refine(50) > 0) step();
    }
    assert.equal(d.finish(), 'ok');
    while (d.refine(50) > 0) step();
    assert.equal(d.faceCount, d.info().fullFaces);
    // Coarsening and refining again report their changes the same way.
    for (const target of [Math.floor(d.faceCount / 3), d.faceCount]) {
      d.setFaceTarget(target);
      step();
    }
    assert.ok(steps > 3, `only ${steps} steps`);
    d.dispose();
  });
}

test('a geometry-only stream gives empty attribute arrays', async () => {
  const { createDecoder } = await importPackage();
  const d = await createDecoder();
  assert.equal(d.feed(readFileSync(path.join(rootDir, 'tests', 'data', 'sample.pmz'))), 'ok');
  assert.equal(d.finish(), 'ok');
  d.refine();
  assert.ok(d.faceCount > 0);
  assert.equal(d.wedgeCount, 0);
  assert.equal(d.texcoordSetCount, 0);
  assert.equal(d.colorComponents, 0);
  assert.equal(d.materialCount, 0);
  for (const a of [d.wedgeVertices(), d.wedgePositions(), d.wedgeIndices(), d.texcoords(),
    d.texcoords(1), d.normals(), d.colors(), d.faceMaterials()])
    assert.equal(a.length, 0);
  assert.deepEqual(d.materials(), []);
  assert.equal(d.changes().wedgeBegin, 0);
  d.dispose();
});
