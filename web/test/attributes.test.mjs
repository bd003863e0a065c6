// SPDX-License-Identifier: MIT
// Attribute arrays of the JavaScript API (format 8.0): texture coordinates, normals, colours,
// wedges and materials are bit-identical to the native decoder's (pmz-dump-arrays, the C API)
// for every byte slicing and at coarser levels; the change report covers the wedges; a
// geometry-only stream gives empty attribute arrays.
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { test } from 'node:test';

import { assimpTextured, encodeNative, importPackage, importThreeLoader, nativeArrays, rootDir,
  sameBits, writeColoredTorus, writeTexturedTorus } from './common.mjs';

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

// The geometry as the loader keeps it against the decoder's render arrays (the wedges).
function assertGeometryMatches(s, what) {
  const d = s.decoder, g = s.geometry, nw = d.wedgeCount, nf = d.faceCount;
  const prefix = (name, n) => g.getAttribute(name).array.subarray(0, n);
  assert.ok(sameBits(prefix('position', 3 * nw), d.wedgePositions()), `${what}: positions`);
  assert.ok(sameBits(g.getIndex().array.subarray(0, 3 * nf), d.wedgeIndices()), `${what}: indices`);
  assert.equal(g.drawRange.count, 3 * nf, `${what}: draw range`);
  const expected = { uv: d.texcoords(0), normal: d.normals(), color: d.colors() };
  for (const [name, a] of Object.entries(expected)) {
    if (!a.length) { assert.equal(g.getAttribute(name), undefined, `${what}: ${name}`); continue; }
    assert.ok(sameBits(prefix(name, a.length), a), `${what}: ${name}`);
  }
  if (d.materialCount > 1) {  // groups: consecutive runs covering every face, one material each
    const fm = d.faceMaterials();
    let next = 0;
    for (const group of g.groups) {
      assert.equal(group.start, 3 * next, `${what}: groups leave a gap`);
      for (let f = next; f < next + group.count / 3; ++f) assert.equal(fm[f], group.materialIndex);
      next += group.count / 3;
    }
    assert.equal(next, nf, `${what}: groups cover ${next} of ${nf} faces`);
  } else {
    assert.equal(g.groups.length, 0);
  }
}

for (const [name, make] of Object.entries(streams)) {
  test(`${name}: PMZStream's geometry draws the wedges, updated in place`, async (t) => {
    const file = make();
    if (!file) return t.skip('corpus-assimp/ missing (scripts/fetch_assimp_models.sh)');
    const { createDecoder } = await importPackage();
    const { PMZStream, pmzMaterials } = await importThreeLoader();
    const s = new PMZStream(await createDecoder(), { geomorph: true });
    const bytes = readFileSync(file);
    let checks = 0;
    for (let at = 0; at < bytes.length; at += 2048) {
      assert.equal(s.feed(bytes.subarray(at, at + 2048)), 'ok');
      s.update(0.2);  // a few splits at a time
      if (s.decoder.wedgeCount) { assertGeometryMatches(s, `at byte ${at}`); ++checks; }
    }
    assert.equal(s.finish(), 'ok');
    while (!s.complete) s.update(5);
    assertGeometryMatches(s, 'complete');
    // Geomorphs per wedge: a wedge streamed with its new vertex starts at the vertex's split
    // parent; others (base, full uploads, new wedges of older vertices) where they are.
    {
      const d = s.decoder, p = d.positions(), parents = d.splitParents(), wv = d.wedgeVertices();
      const morph = s.geometry.getAttribute('pmzMorph').array;
      const at = (w, v) => [0, 1, 2].every((k) => morph[4 * w + k] === p[3 * v + k]);
      let gliding = 0;
      for (let w = 0; w < d.wedgeCount; ++w) {
        const v = wv[w], born = morph[4 * w + 3] > -1e5;
        if (born && parents[v] !== 0xffffffff && at(w, parents[v])) ++gliding;
        else assert.ok(at(w, v), `wedge ${w} starts neither at its vertex nor at its parent`);
      }
      assert.ok(gliding > d.wedgeCount / 4, `${gliding} of ${d.wedgeCount} wedges glide`);
    }
    s.faceTarget = Math.floor(s.faceCount / 3);
    s.update();
    assertGeometryMatches(s, 'coarsened');
    s.faceTarget = null;
    while (s.update(5)) { /* refine back */ }
    assert.equal(s.faceCount, s.info().fullFaces);
    assertGeometryMatches(s, 'refined again');
    assert.ok(checks > 1);

    // Materials: one per table entry, textures resolved against the stream's URL.
    s.url = 'http://example.test/models/stream.pmz';
    const urls = [], loads = [];
    const loader = {
      load: (url, onLoad) => {
        const texture = { colorSpace: '' };
        urls.push(url);
        loads.push(() => onLoad(texture));
        return texture;
      },
    };
    const loaded = [];
    const materials = pmzMaterials(s, { textureLoader: loader, onTextureLoad: (t, m) => loaded.push([t, m]) });
    const table = s.materials();
    assert.equal(materials.length, Math.max(1, table.length));
    assert.equal(materials[0].flatShading, !s.decoder.normals().length);
    assert.equal(materials[0].vertexColors, s.decoder.colorComponents > 0);
    const textured = table.filter((m) => m.baseColorTexture);
    assert.equal(urls.length, textured.length);
    for (const [i, m] of textured.entries()) {
      const expected = new URL(m.baseColorTexture.replace(/\\/g, '/'), s.url).href;
      assert.equal(urls[i], expected);
      assert.ok(expected.startsWith('http://example.test/models/'), expected);
    }
    // Until its texture loads a material's map is one white texel (its base colour is drawn);
    // then the texture, sampled as glTF's and MTL's default sampler: repeated, mipmapped.
    const { LinearFilter, LinearMipmapLinearFilter, RepeatWrapping } = await import('three');
    const withMap = materials.filter((m) => m.map);
    assert.equal(withMap.length, textured.length);
    for (const m of withMap) {
      assert.deepEqual([m.map.image.width, m.map.image.height, [...m.map.image.data]], [1, 1, [255, 255, 255, 255]]);
    }
    for (const load of loads) load();
    assert.equal(loaded.length, textured.length);
    for (const [t, m] of loaded) {
      assert.equal(m.map, t);
      assert.deepEqual([t.wrapS, t.wrapT, t.magFilter, t.minFilter, t.colorSpace],
        [RepeatWrapping, RepeatWrapping, LinearFilter, LinearMipmapLinearFilter, 'srgb']);
    }
    s.dispose();
  });
}
